from numba import njit, prange

from . import KERNEL_OPTIONS, ROW_OPTIONS

# Each loop body is a function of its own, compiled as serial code, and the parallel loop
# only calls it: Numba's parallel passes over a body in the loop took most of the
# compiling (docs/performance.md, "Start-up").


@njit(**ROW_OPTIONS)
def _reversed_line(source, fill, target):
    width = source.shape[0]
    for x in range(width):
        target[x] = source[width - 1 - x]
    for x in range(width, target.shape[0]):
        target[x] = fill


@njit(**KERNEL_OPTIONS)
def reversed_lines(lines, fill, out):
    """``out[i]`` = ``lines[i]`` reversed, then ``fill`` to the end of the row (``out`` is
    (N, W + pad) for ``lines`` (N, W)), a line a task."""
    for i in prange(lines.shape[0]):
        _reversed_line(lines[i], fill, out[i])


@njit(**ROW_OPTIONS)
def _doubled_line(source, target):
    for x in range(target.shape[0]):
        target[x] = source[x // 2]


@njit(**KERNEL_OPTIONS)
def doubled(planes, out):
    """``out[k, y, x]`` = ``planes[k, y // 2, x // 2]``: each plane twice as tall and wide,
    cut to ``out``'s size (at most twice the planes'), a row a task."""
    count, height = out.shape[0], out.shape[1]
    for i in prange(count * height):
        k, y = i // height, i % height
        _doubled_line(planes[k, y // 2], out[k, y])

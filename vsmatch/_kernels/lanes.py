"""Steps over one vector of :data:`LANES` float32 candidates, written as LLVM vector code.

A narrow band's loops run over a constant 8 candidates. LLVM unrolls such a loop whole
and leaves it to its SLP vectoriser, which Numba switches off (it miscompiled: numba
PR 8852), so each ran as eight scalar lanes with their masks worked out one by one. These
intrinsics take the same IEEE operations in the same order in each lane, as one vector:
their results are the scalar loops' to the bit.

Arrays are read and written by flat index into their (C-contiguous) data: the caller
makes sure the :data:`LANES` elements from an index lie inside the array.
"""

from llvmlite import ir
from numba import types
from numba.extending import intrinsic

#: Candidates a narrow band's step takes at once: one vector of float32.
LANES = 8

_F32 = ir.FloatType()
_I32 = ir.IntType(32)
_VF = ir.VectorType(_F32, LANES)
_VI = ir.VectorType(_I32, LANES)
_U8 = ir.IntType(8)
#: Loads and stores promise only their element's alignment (a band starts anywhere).
_ALIGN = {_F32: 4, _U8: 1}


class _Lanes:
    """Helpers to build one intrinsic's code: its arguments by position, cast and splat."""

    def __init__(self, context, builder, signature, args):
        self.context, self.builder = context, builder
        self.types, self.args = signature.args, args

    def index(self, i):
        return self.context.cast(self.builder, self.args[i], self.types[i], types.intp)

    def constant_index(self, value):
        return self.context.get_constant(types.intp, value)

    def data(self, i):
        return self.context.make_array(self.types[i])(self.context, self.builder,
                                                      self.args[i]).data

    def pointer(self, i, at, element=_F32):
        """A vector's pointer to array ``i``'s elements from flat index ``at``."""
        element_pointer = self.builder.gep(self.data(i), [at])
        return self.builder.bitcast(element_pointer,
                                    ir.VectorType(element, LANES).as_pointer())

    def load(self, i, at, element=_F32):
        return self.builder.load(self.pointer(i, at, element), align=_ALIGN[element])

    def store(self, value, i, at):
        self.builder.store(value, self.pointer(i, at), align=4)

    def splat(self, value, vector_type):
        builder = self.builder
        one = builder.insert_element(ir.Constant(vector_type, ir.Undefined), value,
                                     ir.Constant(_I32, 0))
        return builder.shuffle_vector(one, ir.Constant(vector_type, ir.Undefined),
                                      ir.Constant(_VI, [0] * LANES))

    def float_lanes(self, i):
        value = self.context.cast(self.builder, self.args[i], self.types[i], types.float32)
        return self.splat(value, _VF)

    def int_lanes(self, i):
        value = self.context.cast(self.builder, self.args[i], self.types[i], types.int32)
        return self.splat(value, _VI)

    def lesser(self, a, b):
        """``a if a < b else b`` in each lane, as the scalar kernels write it."""
        return self.builder.select(self.builder.fcmp_ordered("<", a, b), a, b)


_LANE_NUMBERS = ir.Constant(_VI, list(range(LANES)))


@intrinsic
def add_in_lanes(typingctx, total, size, src, src_at, held, held_at, first, stop, reach,
                 reach_at, k):
    """For each lane d: where ``first <= d < stop`` and ``k <= reach.flat[reach_at + d]``,
    ``total[d] += src.flat[src_at + d]`` and ``size[d] += held.flat[held_at + d]``."""
    sig = types.void(total, size, src, src_at, held, held_at, first, stop, reach, reach_at,
                     k)

    def codegen(context, builder, signature, args):
        v = _Lanes(context, builder, signature, args)
        reach_lanes = builder.zext(v.load(8, v.index(9), _U8), _VI)
        inside = builder.and_(
            builder.and_(builder.icmp_signed(">=", _LANE_NUMBERS, v.int_lanes(6)),
                         builder.icmp_signed("<", _LANE_NUMBERS, v.int_lanes(7))),
            builder.icmp_signed("<=", v.int_lanes(10), reach_lanes))
        zero = ir.Constant(_VF, [0.0] * LANES)
        origin = v.constant_index(0)
        for acc, source, at in ((0, 2, 3), (1, 4, 5)):
            added = builder.select(inside, v.load(source, v.index(at)), zero)
            v.store(builder.fadd(v.load(acc, origin), added), acc, origin)
        return context.get_dummy_value()

    return sig, codegen


@intrinsic
def copy_lanes(typingctx, dst, dst_at, src, src_at):
    """``dst.flat[dst_at:dst_at + LANES] = src.flat[src_at:src_at + LANES]``."""
    sig = types.void(dst, dst_at, src, src_at)

    def codegen(context, builder, signature, args):
        v = _Lanes(context, builder, signature, args)
        v.store(v.load(2, v.index(3)), 0, v.index(1))
        return context.get_dummy_value()

    return sig, codegen


@intrinsic
def divide_lanes(typingctx, dst, dst_at, numerator, denominator):
    """``dst.flat[dst_at:dst_at + LANES] = numerator[:LANES] / denominator[:LANES]``."""
    sig = types.void(dst, dst_at, numerator, denominator)

    def codegen(context, builder, signature, args):
        v = _Lanes(context, builder, signature, args)
        origin = v.constant_index(0)
        v.store(builder.fdiv(v.load(2, origin), v.load(3, origin)), 0, v.index(1))
        return context.get_dummy_value()

    return sig, codegen


@intrinsic
def path_step_lanes(typingctx, cost, out, at, prev, cur, change, change_at, p1a, p1b, p2a,
                    p2b, m, weight, n):
    """One step of the path recursion over a band of ``n`` <= LANES candidates; returns
    the new path minimum. Per lane d, as ``_kernels.scanline`` writes it for one:

        v = cost.flat[at + d] + path_step(prev, d, P1, P2) - m   (P: b where ``change``
        is nonzero at ``change_at + d``, a elsewhere; infinite from ``n`` on),
        cur[d + 1] = v,  out.flat[at + d] += weight * v.

    ``prev`` holds the previous path costs at 1 + d with both ends at 0 and LANES + 1.
    Its lanes are read as the last step stored them, one vector, and shuffled against
    the two ends for d - 1 and d + 1: loads straddling a vector's store wait until it
    reaches the cache (1.8x slower than the scalar loop)."""
    sig = types.float32(cost, out, at, prev, cur, change, change_at, p1a, p1b, p2a, p2b, m,
                        weight, n)

    def codegen(context, builder, signature, args):
        v = _Lanes(context, builder, signature, args)
        one = v.constant_index(1)
        stay = v.load(3, one)
        prev_data = v.data(3)
        ends = ir.Constant(_VF, ir.Undefined)
        for lane, position in ((0, 0), (1, LANES + 1)):
            end = builder.load(builder.gep(prev_data, [v.constant_index(position)]))
            ends = builder.insert_element(ends, end, ir.Constant(_I32, lane))
        # Lanes 0..7 are ``stay``'s, LANES the lower end, LANES + 1 the upper.
        below = builder.shuffle_vector(stay, ends,
                                       ir.Constant(_VI, [LANES] + list(range(LANES - 1))))
        above = builder.shuffle_vector(stay, ends,
                                       ir.Constant(_VI, list(range(1, LANES)) + [LANES + 1]))
        changes = v.load(5, v.index(6), _U8)
        changed = builder.icmp_unsigned("!=", changes,
                                        ir.Constant(ir.VectorType(_U8, LANES),
                                                    [0] * LANES))
        p1 = builder.select(changed, v.float_lanes(8), v.float_lanes(7))
        p2_total = builder.select(changed, v.float_lanes(10), v.float_lanes(9))
        jump = builder.fadd(v.lesser(below, above), p1)
        best = v.lesser(v.lesser(stay, p2_total), jump)
        at = v.index(2)
        step = builder.fsub(builder.fadd(v.load(0, at), best), v.float_lanes(11))
        inside = builder.icmp_signed("<", _LANE_NUMBERS, v.int_lanes(13))
        step = builder.select(inside, step, ir.Constant(_VF, [float("inf")] * LANES))
        v.store(step, 4, one)
        v.store(builder.fadd(v.load(1, at), builder.fmul(v.float_lanes(12), step)), 1, at)
        # The least of the lanes: path costs are >= 0, where float32 orders as int32.
        bits = builder.bitcast(step, _VI)
        for half in (4, 2, 1):
            other = builder.shuffle_vector(
                bits, ir.Constant(_VI, ir.Undefined),
                ir.Constant(_VI, [(j + half) % LANES for j in range(LANES)]))
            bits = builder.select(builder.icmp_signed("<", bits, other), bits, other)
        return builder.bitcast(builder.extract_element(bits, ir.Constant(_I32, 0)), _F32)

    return sig, codegen

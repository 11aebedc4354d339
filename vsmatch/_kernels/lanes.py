"""Steps over one vector of :data:`LANES` float32 candidates, written as LLVM vector code.

A narrow band's loops run over a constant 8 candidates. LLVM unrolls such a loop whole
and leaves it to its SLP vectoriser, which Numba switches off (it miscompiled: numba
PR 8852), so each ran as eight scalar lanes with their masks worked out one by one. These
intrinsics take the same IEEE operations in the same order in each lane, as one vector:
their results are the scalar loops' to the bit.

The whole range's path steps and least cost take the same code a vector at a time. Arrays
are read and written by flat index into their C-contiguous data (checked when a kernel is
compiled, with their element types): the caller makes sure the :data:`LANES` elements from
an index lie inside the array.
"""

from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.core.errors import TypingError
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


def _arrays(**expected):
    """Refuse, at compile time, an argument that is not a C-contiguous array of the dtype
    named (``name=(array_type, dtype)``): the code reads its data by flat index."""
    for name, (given, dtype) in expected.items():
        if not (isinstance(given, types.Array) and given.dtype == dtype
                and given.layout == "C"):
            raise TypingError(f"lanes: {name} must be a C-contiguous {dtype} array, "
                              f"got {given}")


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

    def element(self, i, at):
        """Array ``i``'s float32 element at flat index ``at``."""
        return self.builder.load(self.builder.gep(self.data(i), [at]))

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
#: The bits of float32 infinity: the least path cost of no candidates.
_INF_BITS = 0x7F800000


@intrinsic
def add_in_lanes(typingctx, total, size, src, src_at, held, held_at, first, stop, reach,
                 reach_at, k):
    """For each lane d: where ``first <= d < stop`` and ``k <= reach.flat[reach_at + d]``,
    ``total[d] += src.flat[src_at + d]`` and ``size[d] += held.flat[held_at + d]``."""
    _arrays(total=(total, types.float32), size=(size, types.float32),
            src=(src, types.float32), held=(held, types.float32), reach=(reach, types.uint8))
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
def add_arm_in_lanes(typingctx, total, size, src, held, first_pass, lo, count, reach, reach_at,
                     base, n, pixel, stride, length):
    """:func:`add_in_lanes` over one arm of a pixel with a band of ``n`` candidates from
    ``base``: for k = 1 .. ``length`` the neighbour at flat pixel index ``pixel + k *
    stride`` (its band ``lo.flat``, ``count.flat`` there) adds, where the two bands meet
    within a vector (offset ``off`` = ``base`` less its ``lo``, -LANES < off < LANES),
    lanes ``max(0, -off) <= d < min(n, its count - off)`` with ``k <= reach.flat[reach_at +
    d]`` of its ``src`` and ``held`` (volumes of one shape, (H, W, depth): its candidates
    from ``off`` on; ones with ``first_pass``) to ``total`` and ``size``: the additions of
    :func:`add_in_lanes` called once a neighbour, in the same order, with the sums kept in
    registers rather than stored and loaded at each neighbour. The caller makes sure each
    neighbour's vector lies inside ``src``."""
    _arrays(total=(total, types.float32), size=(size, types.float32),
            src=(src, types.float32), held=(held, types.float32), lo=(lo, types.int32),
            count=(count, types.int32), reach=(reach, types.uint8))
    if src.ndim != 3:
        raise TypingError(f"lanes: src must be a volume (H, W, depth), got {src}")
    sig = types.void(total, size, src, held, first_pass, lo, count, reach, reach_at, base, n,
                     pixel, stride, length)

    def codegen(context, builder, signature, args):
        v = _Lanes(context, builder, signature, args)
        origin = v.constant_index(0)
        sums = cgutils.alloca_once(builder, _VF)
        sizes = cgutils.alloca_once(builder, _VF)
        builder.store(v.load(0, origin), sums)
        builder.store(v.load(1, origin), sizes)
        reach_lanes = builder.zext(v.load(7, v.index(8), _U8), _VI)  # the same for each k
        first_pass = context.cast(builder, args[4], signature.args[4], types.boolean)
        base, n, pixel, stride = (v.index(i) for i in (9, 10, 11, 12))
        n32 = builder.trunc(n, _I32)
        zero, ones = ir.Constant(_VF, [0.0] * LANES), ir.Constant(_VF, [1.0] * LANES)
        int_zero = ir.Constant(_I32, 0)
        source = context.make_array(signature.args[2])(context, builder, args[2])
        depth = builder.extract_value(source.shape, 2)

        def arm_loop(counting):
            """The loop over k; ``counting`` (the first pass): each lane inside counts as
            one, ``held`` is not read."""
            with cgutils.for_range(builder, v.index(13)) as loop:
                k = builder.add(loop.index, v.constant_index(1))
                neighbour = builder.add(pixel, builder.mul(k, stride))
                off = builder.sub(base, builder.sext(builder.load(
                    builder.gep(v.data(5), [neighbour])), base.type))
                meets = builder.and_(builder.icmp_signed(">", off, v.constant_index(-LANES)),
                                     builder.icmp_signed("<", off, v.constant_index(LANES)))
                with builder.if_then(meets, likely=True):
                    off32 = builder.trunc(off, _I32)
                    first = builder.sub(int_zero, off32)
                    first = builder.select(builder.icmp_signed(">", first, int_zero), first,
                                           int_zero)
                    stop = builder.sub(builder.load(builder.gep(v.data(6), [neighbour])),
                                       off32)
                    stop = builder.select(builder.icmp_signed("<", n32, stop), n32, stop)
                    inside = builder.and_(
                        builder.and_(
                            builder.icmp_signed(">=", _LANE_NUMBERS, v.splat(first, _VI)),
                            builder.icmp_signed("<", _LANE_NUMBERS, v.splat(stop, _VI))),
                        builder.icmp_signed("<=", v.splat(builder.trunc(k, _I32), _VI),
                                            reach_lanes))
                    at = builder.add(builder.mul(neighbour, depth), off)
                    added = builder.select(inside, v.load(2, at), zero)
                    builder.store(builder.fadd(builder.load(sums), added), sums)
                    held_lanes = ones if counting else v.load(3, at)
                    builder.store(builder.fadd(builder.load(sizes),
                                               builder.select(inside, held_lanes, zero)),
                                  sizes)

        with builder.if_else(first_pass) as (in_first_pass, in_second_pass):
            with in_first_pass:
                arm_loop(True)
            with in_second_pass:
                arm_loop(False)
        v.store(builder.load(sums), 0, origin)
        v.store(builder.load(sizes), 1, origin)
        return context.get_dummy_value()

    return sig, codegen


@intrinsic
def copy_lanes(typingctx, dst, dst_at, src, src_at):
    """``dst.flat[dst_at:dst_at + LANES] = src.flat[src_at:src_at + LANES]``."""
    _arrays(dst=(dst, types.float32), src=(src, types.float32))
    sig = types.void(dst, dst_at, src, src_at)

    def codegen(context, builder, signature, args):
        v = _Lanes(context, builder, signature, args)
        v.store(v.load(2, v.index(3)), 0, v.index(1))
        return context.get_dummy_value()

    return sig, codegen


@intrinsic
def divide_lanes(typingctx, dst, dst_at, numerator, denominator):
    """``dst.flat[dst_at:dst_at + LANES] = numerator[:LANES] / denominator[:LANES]``."""
    _arrays(dst=(dst, types.float32), numerator=(numerator, types.float32),
            denominator=(denominator, types.float32))
    sig = types.void(dst, dst_at, numerator, denominator)

    def codegen(context, builder, signature, args):
        v = _Lanes(context, builder, signature, args)
        origin = v.constant_index(0)
        v.store(builder.fdiv(v.load(2, origin), v.load(3, origin)), 0, v.index(1))
        return context.get_dummy_value()

    return sig, codegen


def _path_costs(v, below, stay, above, changes, penalties, cost, m):
    """The recursion's new path costs of one vector of candidates, from the previous ones
    at d - 1, d and d + 1, as ``_kernels.scanline.path_step`` takes them lane by lane:
    ``cost + min(stay, P2 + min, min(below, above) + P1) - m``, with (p1b, p2b) where
    ``changes`` is nonzero, (p1a, p2a) elsewhere (``penalties``: the four as vectors)."""
    builder = v.builder
    p1a, p1b, p2a, p2b = penalties
    changed = builder.icmp_unsigned("!=", changes,
                                    ir.Constant(ir.VectorType(_U8, LANES), [0] * LANES))
    jump = builder.fadd(v.lesser(below, above), builder.select(changed, p1b, p1a))
    best = v.lesser(v.lesser(stay, builder.select(changed, p2b, p2a)), jump)
    return builder.fsub(builder.fadd(cost, best), m)


#: The lane offsets a reduction across the lanes pairs lanes at, halving each time.
_HALVES = (LANES // 2, LANES // 4, 1)


def _turned(builder, vector, half):
    """``vector`` with each lane j holding lane j + ``half`` (round the end)."""
    return builder.shuffle_vector(vector, ir.Constant(vector.type, ir.Undefined),
                                  ir.Constant(_VI, [(j + half) % LANES for j in range(LANES)]))


def _least(builder, bits):
    """The least of a vector of int32, in lane 0 of the result."""
    for half in _HALVES:
        other = _turned(builder, bits, half)
        bits = builder.select(builder.icmp_signed("<", bits, other), bits, other)
    return bits


def _float_of_least(builder, bits):
    """Path costs are >= 0, where float32 orders as int32: their least as a float."""
    return builder.bitcast(builder.extract_element(_least(builder, bits),
                                                   ir.Constant(_I32, 0)), _F32)


@intrinsic
def path_step_lanes(typingctx, cost, out, at, paths, prev_at, cur_at, change, change_at, p1a,
                    p1b, p2a, p2b, m, weight, n):
    """One step of the path recursion over a band of ``n`` <= LANES candidates; returns
    the new path minimum. Per lane d, as ``_kernels.scanline`` writes it for one:

        v = cost.flat[at + d] + path_step(prev, d, P1, P2) - m   (P: b where ``change``
        is nonzero at ``change_at + d``, a elsewhere; infinite from ``n`` on),
        cur[d + 1] = v,  out.flat[at + d] += weight * v,

    where ``prev`` and ``cur`` are the LANES + 2 path costs of ``paths`` from flat index
    ``prev_at`` and ``cur_at`` (one array for both: a view of its rows would cost two
    atomic reference counts a step). ``prev`` holds the previous path costs at 1 + d with
    both ends at 0 and LANES + 1. Its lanes are read as the last step stored them, one
    vector, and shuffled against the two ends for d - 1 and d + 1: loads straddling a
    vector's store wait until it reaches the cache (three such loads made the step 1.8x
    slower than the scalar loop)."""
    _arrays(cost=(cost, types.float32), out=(out, types.float32),
            paths=(paths, types.float32), change=(change, types.uint8))
    sig = types.float32(cost, out, at, paths, prev_at, cur_at, change, change_at, p1a, p1b,
                        p2a, p2b, m, weight, n)

    def codegen(context, builder, signature, args):
        v = _Lanes(context, builder, signature, args)
        prev = v.index(4)
        one = v.constant_index(1)
        stay = v.load(3, builder.add(prev, one))
        ends = ir.Constant(_VF, ir.Undefined)
        for lane, position in ((0, 0), (1, LANES + 1)):
            ends = builder.insert_element(
                ends, v.element(3, builder.add(prev, v.constant_index(position))),
                ir.Constant(_I32, lane))
        # Lanes 0..7 are ``stay``'s, LANES the lower end, LANES + 1 the upper.
        below = builder.shuffle_vector(stay, ends,
                                       ir.Constant(_VI, [LANES] + list(range(LANES - 1))))
        above = builder.shuffle_vector(stay, ends,
                                       ir.Constant(_VI, list(range(1, LANES)) + [LANES + 1]))
        at = v.index(2)
        step = _path_costs(v, below, stay, above, v.load(6, v.index(7), _U8),
                           [v.float_lanes(i) for i in (8, 9, 10, 11)], v.load(0, at),
                           v.float_lanes(12))
        inside = builder.icmp_signed("<", _LANE_NUMBERS, v.int_lanes(14))
        step = builder.select(inside, step, ir.Constant(_VF, [float("inf")] * LANES))
        v.store(step, 3, builder.add(v.index(5), one))
        v.store(builder.fadd(v.load(1, at), builder.fmul(v.float_lanes(13), step)), 1, at)
        return _float_of_least(builder, builder.bitcast(step, _VI))

    return sig, codegen


def _path_step_chunks(write):
    """:func:`path_step_lanes` over the whole of a pixel's ``chunks`` x LANES candidates
    (the whole range, or a band wider than a vector), a vector at a time; with ``write``
    the step writes ``weight`` x its path costs to ``out`` rather than adds them."""

    @intrinsic
    def path_step_chunks(typingctx, cost, out, at, paths, prev_at, cur_at, change, change_at,
                         p1a, p1b, p2a, p2b, m, weight, chunks):
        """Candidates 0 .. LANES x ``chunks`` - 1 of one step of the path recursion
        (``_kernels.scanline``'s ``next_step``, the same operations lane by lane) from the
        pixel's costs at flat index ``at`` of ``cost`` and ``out`` and its changes at
        ``change_at`` of ``change``; returns their least path cost (infinite without
        chunks). ``paths``: the previous path costs from ``prev_at`` (at 1 + d, the lower
        end at 0), read a vector at a time as the last step stored them, each vector's
        neighbours shuffled in from the next and the last one (loads straddling two
        vectors' stores wait until they reach the cache), the new ones written from
        ``cur_at``."""
        _arrays(cost=(cost, types.float32), out=(out, types.float32),
                paths=(paths, types.float32), change=(change, types.uint8))
        sig = types.float32(cost, out, at, paths, prev_at, cur_at, change, change_at, p1a,
                            p1b, p2a, p2b, m, weight, chunks)

        def codegen(context, builder, signature, args):
            v = _Lanes(context, builder, signature, args)
            at, prev, cur, change_at = v.index(2), v.index(4), v.index(5), v.index(7)
            n_chunks = v.index(14)
            one = v.constant_index(1)
            # Carried from vector to vector: the last one's path costs (its lane 7 is the
            # lower neighbour of this one's lane 0), this one's, the least so far.
            behind = cgutils.alloca_once(builder, _VF)
            here = cgutils.alloca_once(builder, _VF)
            least = cgutils.alloca_once(builder, _VI)
            lower_end = v.element(3, prev)
            builder.store(builder.insert_element(ir.Constant(_VF, ir.Undefined), lower_end,
                                                 ir.Constant(_I32, LANES - 1)), behind)
            builder.store(v.load(3, builder.add(prev, one)), here)
            builder.store(ir.Constant(_VI, [_INF_BITS] * LANES), least)
            penalties = [v.float_lanes(i) for i in (8, 9, 10, 11)]
            m, w = v.float_lanes(12), v.float_lanes(13)
            with cgutils.for_range(builder, n_chunks) as loop:
                base = builder.mul(loop.index, v.constant_index(LANES))
                next_base = builder.add(builder.add(prev, base),
                                        v.constant_index(LANES + 1))
                stay = builder.load(here)
                is_last = builder.icmp_signed(">=", builder.add(loop.index, one), n_chunks)
                with builder.if_else(is_last) as (last, more):
                    with last:  # the next path cost past the vectors: one element
                        ahead_last = builder.insert_element(
                            ir.Constant(_VF, ir.Undefined), v.element(3, next_base),
                            ir.Constant(_I32, 0))
                        last_block = builder.block
                    with more:
                        ahead_more = v.load(3, next_base)
                        more_block = builder.block
                ahead = builder.phi(_VF)
                ahead.add_incoming(ahead_last, last_block)
                ahead.add_incoming(ahead_more, more_block)
                below = builder.shuffle_vector(
                    builder.load(behind), stay,
                    ir.Constant(_VI, [LANES - 1] + list(range(LANES, 2 * LANES - 1))))
                above = builder.shuffle_vector(
                    stay, ahead, ir.Constant(_VI, list(range(1, LANES)) + [LANES]))
                cell = builder.add(at, base)
                step = _path_costs(v, below, stay, above,
                                   v.load(6, builder.add(change_at, base), _U8), penalties,
                                   v.load(0, cell), m)
                v.store(step, 3, builder.add(builder.add(cur, base), one))
                weighted = builder.fmul(w, step)
                if not write:
                    weighted = builder.fadd(v.load(1, cell), weighted)
                v.store(weighted, 1, cell)
                bits = builder.bitcast(step, _VI)
                so_far = builder.load(least)
                builder.store(builder.select(builder.icmp_signed("<", bits, so_far), bits,
                                             so_far), least)
                builder.store(stay, behind)
                builder.store(ahead, here)
            return _float_of_least(builder, builder.load(least))

        return sig, codegen

    return path_step_chunks


path_step_chunks_write = _path_step_chunks(True)
path_step_chunks_add = _path_step_chunks(False)


@intrinsic
def argmin_chunks(typingctx, costs, chunks):
    """The index of the least of ``costs[:LANES * chunks]`` (``chunks`` >= 1), the first
    where several are equal, as a scalar walk with ``<`` finds it (for costs without
    NaN): each lane keeps its first least, then the lanes' least, the earliest of equals."""
    _arrays(costs=(costs, types.float32))
    sig = types.int64(costs, chunks)

    def codegen(context, builder, signature, args):
        v = _Lanes(context, builder, signature, args)
        n_chunks = v.index(1)
        values = cgutils.alloca_once(builder, _VF)
        places = cgutils.alloca_once(builder, _VI)
        builder.store(v.load(0, v.constant_index(0)), values)
        builder.store(_LANE_NUMBERS, places)
        with cgutils.for_range(builder, builder.sub(n_chunks, v.constant_index(1))) as loop:
            chunk = builder.add(loop.index, v.constant_index(1))
            base = builder.mul(chunk, v.constant_index(LANES))
            candidate = v.load(0, base)
            held = builder.load(values)
            take = builder.fcmp_ordered("<", candidate, held)
            builder.store(builder.select(take, candidate, held), values)
            here = builder.add(v.splat(builder.trunc(base, _I32), _VI), _LANE_NUMBERS)
            builder.store(builder.select(take, here, builder.load(places)), places)
        value, place = builder.load(values), builder.load(places)
        for half in _HALVES:
            other_value = _turned(builder, value, half)
            other_place = _turned(builder, place, half)
            earlier_equal = builder.and_(builder.fcmp_ordered("==", other_value, value),
                                         builder.icmp_signed("<", other_place, place))
            take = builder.or_(builder.fcmp_ordered("<", other_value, value), earlier_equal)
            value = builder.select(take, other_value, value)
            place = builder.select(take, other_place, place)
        first = builder.extract_element(place, ir.Constant(_I32, 0))
        return builder.sext(first, ir.IntType(64))

    return sig, codegen

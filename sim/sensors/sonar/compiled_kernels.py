"""The compiled kernels behind :mod:`sim.sensors.sonar.fused_passes` (numba, cached on disk).

Module-level functions, so numba's on-disk cache finds them in every process; imported on
first use through :func:`sim.sensors.sonar.fused_passes.kernels`.
"""

from __future__ import annotations

import numba as nb
import numpy as np
from llvmlite import ir
from numba.core import types
from numba.extending import intrinsic

f32 = np.float32
u64 = np.uint64
u32 = np.uint32
TWO_M24 = f32(2.0 ** -24)  # the float32 uniform's grid step
LOW32 = u64(0xFFFFFFFF)


@intrinsic
def lcg128(typingctx, x_hi, x_lo, a_hi, a_lo, c_hi, c_lo):
    """``a x + c`` mod 2^128 of 128-bit numbers held as (hi, lo) uint64 pairs, in LLVM's i128
    arithmetic (three multiplies on x86-64); returns (hi, lo)."""
    sig = types.UniTuple(types.uint64, 2)(types.uint64, types.uint64, types.uint64, types.uint64,
                                          types.uint64, types.uint64)

    def codegen(context, builder, signature, args):
        i128, i64 = ir.IntType(128), ir.IntType(64)
        sh = ir.Constant(i128, 64)

        def join(hi, lo):
            return builder.or_(builder.shl(builder.zext(hi, i128), sh), builder.zext(lo, i128))

        y = builder.add(builder.mul(join(args[0], args[1]), join(args[2], args[3])), join(args[4], args[5]))
        hi, lo = builder.trunc(builder.lshr(y, sh), i64), builder.trunc(y, i64)
        return context.make_tuple(builder, signature.return_type, (hi, lo))

    return sig, codegen


@nb.njit(cache=True, nogil=True, inline="always")
def xsl_rr(hi, lo):
    """PCG's XSL-RR output of a 128-bit state: ``rotr64(hi ^ lo, hi >> 58)``."""
    v = hi ^ lo
    r = hi >> u64(58)
    return (v >> r) | (v << ((u64(64) - r) & u64(63)))


@nb.njit(cache=True, nogil=True, inline="always")
def complement_of_word(w32):
    """``1 - U`` of a float32 uniform ``U = (w >> 8) 2^-24`` (``w`` a uint32 in a uint64), exact."""
    return f32(np.int64(16777216) - np.int64(w32 >> u64(8))) * TWO_M24


@nb.njit(cache=True, nogil=True)
def pcg64_complement_uniform_f32(s_hi, s_lo, m_hi, m_lo, inc_hi, inc_lo, jump_m, jump_c, first, has_first, out):
    """:func:`complement_uniform_f32` drawing its words straight from a PCG64 state.

    numpy's PCG64 step is ``s <- M s + inc`` (mod 2^128), then the output ``xsl_rr(s)``; a
    uint64 gives two uint32 words, low half first. The states are the same whatever order
    they are computed in, so four chains run side by side, each stepping four states at a
    time with ``jump_m = M^4`` and ``jump_c = (M^3 + M^2 + M + 1) inc`` ((hi, lo) pairs):
    independent multiplies instead of one long dependency chain. Returns the last state
    stepped to (hi, lo) and the high half of the last uint64 drawn (the spare word numpy
    buffers when the count is odd).
    """
    o = out.ravel()
    n = o.size
    j0 = 0
    if has_first:
        o[0] = complement_of_word(u64(first))
        j0 = 1
    need = n - j0
    n64 = (need + 1) // 2
    # the first four states after s
    h0, l0 = lcg128(s_hi, s_lo, m_hi, m_lo, inc_hi, inc_lo)
    h1, l1 = lcg128(h0, l0, m_hi, m_lo, inc_hi, inc_lo)
    h2, l2 = lcg128(h1, l1, m_hi, m_lo, inc_hi, inc_lo)
    h3, l3 = lcg128(h2, l2, m_hi, m_lo, inc_hi, inc_lo)
    a_hi, a_lo = jump_m
    c_hi, c_lo = jump_c
    last_hi, last_lo, spare = s_hi, s_lo, u64(0)
    i = 0
    full = need // 2  # uint64 draws whose both halves are used
    while i + 4 <= full:
        w0, w1, w2, w3 = xsl_rr(h0, l0), xsl_rr(h1, l1), xsl_rr(h2, l2), xsl_rr(h3, l3)
        k = j0 + 2 * i
        o[k] = complement_of_word(w0 & LOW32)
        o[k + 1] = complement_of_word(w0 >> u64(32))
        o[k + 2] = complement_of_word(w1 & LOW32)
        o[k + 3] = complement_of_word(w1 >> u64(32))
        o[k + 4] = complement_of_word(w2 & LOW32)
        o[k + 5] = complement_of_word(w2 >> u64(32))
        o[k + 6] = complement_of_word(w3 & LOW32)
        o[k + 7] = complement_of_word(w3 >> u64(32))
        last_hi, last_lo, spare = h3, l3, w3 >> u64(32)
        h0, l0 = lcg128(h0, l0, a_hi, a_lo, c_hi, c_lo)
        h1, l1 = lcg128(h1, l1, a_hi, a_lo, c_hi, c_lo)
        h2, l2 = lcg128(h2, l2, a_hi, a_lo, c_hi, c_lo)
        h3, l3 = lcg128(h3, l3, a_hi, a_lo, c_hi, c_lo)
        i += 4
    # the rest one state at a time, from the next state in order (chain 0's)
    h, l = h0, l0
    while i < n64:
        w = xsl_rr(h, l)
        k = j0 + 2 * i
        o[k] = complement_of_word(w & LOW32)
        if k + 1 < n:
            o[k + 1] = complement_of_word(w >> u64(32))
        last_hi, last_lo, spare = h, l, w >> u64(32)
        h, l = lcg128(h, l, m_hi, m_lo, inc_hi, inc_lo)
        i += 1
    return last_hi, last_lo, spare


@nb.njit(cache=True, nogil=True)
def complement_uniform_f32(raw32, first, has_first, out):
    """``1 - U`` for float32 uniforms ``U = (w >> 8) 2^-24`` of the uint32 words ``raw32``
    (after ``first`` when ``has_first``), as numpy's ``Generator.random(dtype=float32)``
    forms them; exact: ``1 - k 2^-24 = (2^24 - k) 2^-24``."""
    o = out.ravel()
    j = 0
    if has_first:
        o[0] = f32(16777216 - (first >> 8)) * TWO_M24
        j = 1
    for i in range(o.size - j):
        o[i + j] = f32(16777216 - (raw32[i] >> 8)) * TWO_M24


@nb.njit(cache=True, nogil=True)
def scale_by_neg(mean, add, log_u, out):
    """``out = (mean + add) * -log_u`` element-wise, float32 (``-log(1 - U)`` is Exp(1))."""
    m, lu, o = mean.ravel(), log_u.ravel(), out.ravel()
    a = f32(add)
    for i in range(o.size):
        o[i] = (m[i] + a) * -lu[i]


@nb.njit(cache=True, nogil=True)
def gain_floor(x, gain, floor, out):
    """``out = max(x * gain[None, :], floor)`` of a (rows, cols) float32 array."""
    rows, cols = x.shape
    lo = f32(floor)
    for r in range(rows):
        for c in range(cols):
            v = x[r, c] * gain[c]
            out[r, c] = lo if v < lo else v  # np.maximum's: NaN stays NaN


@nb.njit(cache=True, nogil=True)
def remap_bilinear_u8(src, dst_flat, dst_idx, base, frac, step, wtab):
    """Fixed-point bilinear gather (``cv2.remap`` with ``CV_16SC2`` maps on 8-bit images):
    ``dst[dst_idx] = (sum_k w_k p_k + 2^14) >> 15`` over the 2 x 2 neighbours of ``base``;
    ``step`` bit 0 / bit 1: the right / lower neighbour exists (else its weight is 0)."""
    p = src.ravel()
    w = src.shape[1]
    for i in range(dst_idx.size):
        b = base[i]
        s = step[i]
        dx = 1 if s & 1 else 0
        dy = w if s & 2 else 0
        t = frac[i]
        acc = (np.int32(p[b]) * wtab[t, 0] + np.int32(p[b + dx]) * wtab[t, 1]
               + np.int32(p[b + dy]) * wtab[t, 2] + np.int32(p[b + dy + dx]) * wtab[t, 3])
        dst_flat[dst_idx[i]] = (acc + 16384) >> 15


@nb.njit(cache=True, nogil=True)
def gather(src, dst_flat, dst_idx, src_idx):
    """``dst_flat[dst_idx] = src.ravel()[src_idx]`` (nearest-neighbour resampling)."""
    p = src.ravel()
    for i in range(dst_idx.size):
        dst_flat[dst_idx[i]] = p[src_idx[i]]


@nb.njit(cache=True, nogil=True)
def spread_segments(n_rows, n_bins, row, u_a, u_b, energy, out):
    """:func:`sim.sensors.sonar.echo_lines.spread_segments` in three passes: the kinks in
    the order ``np.bincount`` met them (so each bin's float64 sum adds the same terms in the
    same order), then per row the prefix sums as ``cv2.integral`` forms them (running row
    sum added to the previous row's integral) and their row differences in ``out``'s type,
    floored at 0."""
    stride = n_bins + 2
    acc = np.zeros(n_rows * stride)
    m = row.size
    nb_f = float(n_bins)
    # segments: +w at fl + 1, then the fractional terms (lower ends first, then upper ends)
    for part in range(3):
        for end in range(2):
            for i in range(m):
                lo, hi = min(u_a[i], u_b[i]), max(u_a[i], u_b[i])
                length = hi - lo
                if length < 1e-9 or not (hi > 0.0) or not (lo < nb_f):
                    continue
                density = energy[i] / length
                p = min(max(lo if end == 0 else hi, 0.0), nb_f)
                w = density if end == 0 else -density
                fl = np.floor(p)
                base = row[i] * stride + int(fl)
                if part == 0:
                    acc[base + 1] += w
                else:
                    off = w * (1.0 - (p - fl))
                    if part == 1:
                        acc[base] += off
                    else:
                        acc[base + 1] += -off
    # points: +E at their bin, -E at the next
    for part in range(2):
        for i in range(m):
            lo, hi = min(u_a[i], u_b[i]), max(u_a[i], u_b[i])
            if not (hi - lo < 1e-9):
                continue
            kp = np.floor(lo)
            if not (kp >= 0.0 and kp < nb_f):
                continue
            base = row[i] * stride + int(kp)
            if part == 0:
                acc[base] += energy[i]
            else:
                acc[base + 1] += -energy[i]
    prev = np.zeros(stride)  # the integral's previous row
    zero = out.dtype.type(0)
    r = 0
    while r + 4 <= n_rows:  # four rows at a time: four independent running sums
        s0 = s1 = s2 = s3 = 0.0
        a0, a1, a2, a3 = r * stride, (r + 1) * stride, (r + 2) * stride, (r + 3) * stride
        for x in range(n_bins):
            s0 += acc[a0 + x]
            s1 += acc[a1 + x]
            s2 += acc[a2 + x]
            s3 += acc[a3 + x]
            p = prev[x]
            c0 = p + s0
            c1 = c0 + s1
            c2 = c1 + s2
            c3 = c2 + s3
            t = out.dtype.type(p)
            t0 = out.dtype.type(c0)
            t1 = out.dtype.type(c1)
            t2 = out.dtype.type(c2)
            t3 = out.dtype.type(c3)
            v0, v1, v2, v3 = t0 - t, t1 - t0, t2 - t1, t3 - t2
            out[r, x] = zero if v0 < zero else v0
            out[r + 1, x] = zero if v1 < zero else v1
            out[r + 2, x] = zero if v2 < zero else v2
            out[r + 3, x] = zero if v3 < zero else v3
            prev[x] = c3
        r += 4
    while r < n_rows:
        s0 = 0.0
        for x in range(n_bins):
            s0 += acc[r * stride + x]
            c0 = prev[x] + s0
            v0 = out.dtype.type(c0) - out.dtype.type(prev[x])
            out[r, x] = zero if v0 < zero else v0
            prev[x] = c0
        r += 1


@nb.njit(cache=True, nogil=True, inline="always")
def row_dot3(a, i, b, j):
    """``a[i] . b[j]`` of two (N, 3) arrays summed as ``np.einsum("ij,ij->i")`` sums three
    terms: ``(a0 b0 + a2 b2) + a1 b1``."""
    return (a[i, 0] * b[j, 0] + a[i, 2] * b[j, 2]) + a[i, 1] * b[j, 1]


@nb.njit(cache=True, nogil=True)
def same_surface_pair(da, db, same_obj, va0, va1, va2, vb0, vb1, vb2, na0, na1, na2, nb0, nb1, nb2, chord_sin):
    """:func:`sim.sensors.sonar.ray_fan.same_surface` of one pair of hits (ranges, whether the
    object ids match, directions and normals by component), with the same float64 operations
    (dot products summed as :func:`row_dot3` sums them). Scalars only: LLVM inlines it (a
    call passing arrays would cost more than the test)."""
    if not (np.isfinite(da) and np.isfinite(db) and same_obj):
        return False
    c0 = db * vb0 - da * va0
    c1 = db * vb1 - da * va1
    c2 = db * vb2 - da * va2
    tol = chord_sin * np.sqrt((c0 * c0 + c2 * c2) + c1 * c1) + 1e-9
    return abs((c0 * na0 + c2 * na2) + c1 * na1) <= tol and abs((c0 * nb0 + c2 * nb2) + c1 * nb1) <= tol


@nb.njit(cache=True, nogil=True)
def same_surface(d_a, n_a, o_a, v_a, ia, d_b, n_b, o_b, v_b, ib, chord_sin):
    """:func:`sim.sensors.sonar.ray_fan.same_surface` of rows ``ia`` of the a arrays and
    ``ib`` of the b arrays, with the same float64 operations."""
    out = np.zeros(ia.size, dtype=np.bool_)
    for k in range(ia.size):
        i, j = ia[k], ib[k]
        out[k] = same_surface_pair(d_a[i], d_b[j], o_a[i] == o_b[j], v_a[i, 0], v_a[i, 1], v_a[i, 2], v_b[j, 0],
                                   v_b[j, 1], v_b[j, 2], n_a[i, 0], n_a[i, 1], n_a[i, 2], n_b[j, 0], n_b[j, 1],
                                   n_b[j, 2], chord_sin)
    return out


@nb.njit(cache=True, nogil=True)
def bisect_level(lo_d, lo_n, lo_o, lo_v, lo_p, lo_row, hi_d, hi_p, hi_row, act, mid_d, mid_n, mid_o, mid_v,
                 mid_p, mid_row0, chord_sin):
    """One level of :meth:`sim.sensors.sonar.ray_fan.RayFan.bisect`, in place: the mid ray
    ``k`` of interval ``act[k]`` replaces its lower end where it lies on that end's surface or
    both miss (else its upper end); ``lo_row``/``hi_row`` take its pool row ``mid_row0 + k``."""
    for k in range(act.size):
        i = act[k]
        with_lo = same_surface_pair(lo_d[i], mid_d[k], lo_o[i] == mid_o[k], lo_v[i, 0], lo_v[i, 1], lo_v[i, 2],
                                    mid_v[k, 0], mid_v[k, 1], mid_v[k, 2], lo_n[i, 0], lo_n[i, 1], lo_n[i, 2],
                                    mid_n[k, 0], mid_n[k, 1], mid_n[k, 2], chord_sin)
        if not with_lo and not np.isfinite(lo_d[i]) and not np.isfinite(mid_d[k]):
            with_lo = True
        if with_lo:
            lo_d[i], lo_o[i], lo_p[i], lo_row[i] = mid_d[k], mid_o[k], mid_p[k], mid_row0 + k
            for c in range(3):
                lo_n[i, c] = mid_n[k, c]
                lo_v[i, c] = mid_v[k, c]
        else:
            hi_d[i], hi_p[i], hi_row[i] = mid_d[k], mid_p[k], mid_row0 + k

@nb.njit(cache=True, nogil=True, error_model="numpy")  # IEEE division: x / 0 -> inf or nan, as numpy
def echo_segments(seg_a, seg_b, conn, col, phi, dist, obj, strength, range_slope, window_near, resolution):
    """:func:`sim.sensors.sonar.echo_lines.echo_segments` in one pass per part, with the same
    float64 operations in the same order and its rows in its order (connected intervals' first
    parts, the second parts of folded ones, then the unconnected upper ends and lower ends),
    dropping rows without positive ranges and energy. Returns (line, u0, u1, energy, obj)."""
    m = seg_a.size
    n_conn = 0
    for k in range(m):
        if conn[k]:
            n_conn += 1
    cap = n_conn * 2 + (m - n_conn) * 2
    o_line = np.empty(cap, dtype=np.intp)
    o_u0, o_u1, o_e = np.empty(cap), np.empty(cap), np.empty(cap)
    o_obj = np.empty(cap, dtype=np.int64)
    # per connected interval: its fold's range extremum and split (t_ext = 1: no fold)
    f_r_ext, f_t, f_fold = np.empty(n_conn), np.empty(n_conn), np.zeros(n_conn, dtype=np.bool_)
    f_e, f_rb = np.empty(n_conn), np.empty(n_conn)
    f_row = np.empty(n_conn, dtype=np.intp)
    f_obj = np.empty(n_conn, dtype=np.int64)
    n = 0
    j = 0
    for k in range(m):
        if not conn[k]:
            continue
        a, b = seg_a[k], seg_b[k]
        dc = phi[b] - phi[a]
        e_conn = 0.5 * (strength[a] + strength[b]) * dc
        ra = dist[a] if np.isfinite(dist[a]) else 0.0
        rb = dist[b] if np.isfinite(dist[b]) else 0.0
        sa, sb = range_slope[a] * dc, range_slope[b] * dc
        dd = ra - rb + sb
        lin = 0.5 * (sa + sb - 2.0 * dd)
        quad = 0.5 * (rb - ra - sa + dd)
        t_ext = -lin / (2.0 * quad)
        fold = sa * sb < 0.0 and t_ext > 0.0 and t_ext < 1.0
        if fold:
            r_ext = ra + lin * t_ext + quad * (t_ext * t_ext)
            # bounded by the end tangents (_clamp_to_end_tangents)
            near, far = min(ra, rb), max(ra, rb)
            t_cross = (rb - sb - ra) / (sa - sb)
            r_cross = ra + sa * t_cross
            crosses = t_cross > 0.0 and t_cross < 1.0
            if sa < 0.0:
                lo = r_cross if crosses else near
                hi = near
            else:
                lo = far
                hi = r_cross if crosses else far
            lo_b, hi_b = min(lo, hi), max(lo, hi)
            r_ext = min(max(r_ext, lo_b), hi_b)
            e_first = e_conn * t_ext
        else:
            t_ext = 1.0
            r_ext = rb
            e_first = e_conn * 1.0
        f_r_ext[j], f_t[j], f_fold[j], f_e[j], f_rb[j] = r_ext, t_ext, fold, e_conn, rb
        f_row[j], f_obj[j] = col[a], obj[a]
        j += 1
        energy = e_first * ra * r_ext
        if ra > 0.0 and r_ext > 0.0 and energy > 0.0:
            o_line[n], o_u0[n], o_u1[n] = col[a], (ra - window_near) / resolution, (r_ext - window_near) / resolution
            o_e[n], o_obj[n] = energy, obj[a]
            n += 1
    for j in range(n_conn):  # the folds' second parts
        if not f_fold[j]:
            continue
        r0, r1 = f_r_ext[j], f_rb[j]
        energy = f_e[j] * (1.0 - f_t[j]) * r0 * r1
        if r0 > 0.0 and r1 > 0.0 and energy > 0.0:
            o_line[n], o_u0[n], o_u1[n] = f_row[j], (r0 - window_near) / resolution, (r1 - window_near) / resolution
            o_e[n], o_obj[n] = energy, f_obj[j]
            n += 1
    for end in range(2):  # unconnected ends: each ray keeps half its share of the gap at its own range
        for k in range(m):
            if conn[k]:
                continue
            r = seg_a[k] if end == 0 else seg_b[k]
            dphi = phi[seg_b[k]] - phi[seg_a[k]]
            rr = dist[r] if np.isfinite(dist[r]) else 0.0
            energy = 0.5 * strength[r] * dphi * rr * rr
            if rr > 0.0 and energy > 0.0:
                u = (rr - window_near) / resolution
                o_line[n], o_u0[n], o_u1[n], o_e[n], o_obj[n] = col[r], u, u, energy, obj[r]
                n += 1
    return o_line[:n], o_u0[:n], o_u1[:n], o_e[:n], o_obj[:n]


@intrinsic
def f32_bits(typingctx, x):
    """The IEEE-754 bits of a float32 as a uint32 (a bit cast, no conversion)."""
    sig = types.uint32(types.float32)

    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], ir.IntType(32))

    return sig, codegen


@nb.njit(cache=True, nogil=True, inline="always")
def mix32(x):
    """Wellons' ``lowbias32`` integer hash of a uint32 (a bijection; [Wellons2018])."""
    x = u32(x ^ (x >> u32(16)))
    x = u32(x * u32(0x7FEB352D))
    x = u32(x ^ (x >> u32(15)))
    x = u32(x * u32(0x846CA68B))
    return u32(x ^ (x >> u32(16)))


@nb.njit(cache=True, nogil=True, inline="always")
def keyed_hash(n, key0, key1):
    """The counter-based draw of element ``n``: ``mix32(mix32(n * 0x9E3779B9 + key0) ^ key1)``
    (uint32 arithmetic; [Salmon2011], [Wellons2018])."""
    return mix32(u32(mix32(u32(u32(u32(n) * u32(0x9E3779B9)) + key0)) ^ key1))


@nb.njit(cache=True, nogil=True)
def counter_speckle_display(mean, add, gain, key0, key1, exp_table, lut, shift, hashes, intensity, out):
    """Counter-based speckle, receiver noise and the display in one pass over (rows, cols).

    Per pair of pixels ``(r, 2j)``, ``(r, 2j + 1)``: ``h = keyed_hash(n, key0, key1)`` with
    ``n = r * ceil(cols / 2) + j``; its low and high 16 bits pick the two pixels'
    unit-mean exponential quantiles ``exp_table[.]``. ``intensity = (mean + add) * e``;
    ``out = lut[bits(intensity * gain[col]) >> shift]`` (the display law tabulated on the
    float's exponent and top mantissa bits). ``hashes``: a scratch uint32 row of
    ``ceil(cols / 2)`` words."""
    rows, cols = mean.shape
    half = hashes.size
    h16 = hashes.view(np.uint16)
    for r in range(rows):
        base = u32(u32(r) * u32(half))
        for j in range(half):
            hashes[j] = keyed_hash(u32(base + u32(j)), key0, key1)
        for c in range(cols):
            v = (mean[r, c] + add) * exp_table[h16[c]]
            intensity[r, c] = v
            out[r, c] = lut[u32(f32_bits(f32(v * gain[c])) >> shift)]


@nb.njit(cache=True, nogil=True)
def triangle_hits(prim, tfar, ng, dirs, tri_geom, geomid, dist, normal):
    """Embree's per-ray results as ``mj_multiRay``'s: ``geomid = tri_geom[prim]`` (-1 where
    ``prim`` < 0, a miss), ``dist = tfar`` (-1 where missed), ``normal`` the unit geometric
    normal ``ng`` turned to face the ray (zeros where missed, or where ``ng`` is 0)."""
    for i in range(prim.size):
        p = prim[i]
        if p < 0:
            geomid[i] = -1
            dist[i] = -1.0
            normal[i, 0] = 0.0
            normal[i, 1] = 0.0
            normal[i, 2] = 0.0
            continue
        geomid[i] = tri_geom[p]
        dist[i] = tfar[i]
        x, y, z = float(ng[i, 0]), float(ng[i, 1]), float(ng[i, 2])
        n = np.sqrt(x * x + y * y + z * z)
        if n > 0.0:
            if x * dirs[i, 0] + y * dirs[i, 1] + z * dirs[i, 2] > 0.0:
                n = -n
            x, y, z = x / n, y / n, z / n
        normal[i, 0] = x
        normal[i, 1] = y
        normal[i, 2] = z


@nb.njit(cache=True, nogil=True)
def counter_k_speckle_display(mean, clutter, add, gain, key0, key1, exp_table, texture_table, lut, shift, intensity,
                              out):
    """:func:`counter_speckle_display` with K-distributed clutter: one hash per pixel
    ``h = keyed_hash(n, key0, key1)``, ``n = r * cols + c``; its low 16
    bits pick the speckle factor ``exp_table[.]``, its top 12 bits the unit-mean Gamma texture
    ``texture_table[.]``, which scales the mean where ``clutter`` (uint8, non-zero)."""
    rows, cols = mean.shape
    for r in range(rows):
        base = u32(u32(r) * u32(cols))
        for c in range(cols):
            h = keyed_hash(u32(base + u32(c)), key0, key1)
            m = mean[r, c]
            if clutter[r, c]:
                m = m * texture_table[h >> u32(20)]
            v = (m + add) * exp_table[h & u32(0xFFFF)]
            intensity[r, c] = v
            out[r, c] = lut[u32(f32_bits(f32(v * gain[c])) >> shift)]

"""Slow, obvious NumPy/Python versions of the kernels, for tests only."""

import numpy as np


def census(grey, half_w, half_h, band=0.0):
    h, w = grey.shape
    out = np.zeros((h, w), dtype=np.uint64)
    for y in range(h):
        for x in range(w):
            bits = 0
            for dy in range(-half_h, half_h + 1):
                for dx in range(-half_w, half_w + 1):
                    if dy == 0 and dx == 0:
                        continue
                    q = grey[min(max(y + dy, 0), h - 1), min(max(x + dx, 0), w - 1)]
                    bits = (bits << 1) | int(q < grey[y, x] - band)
            out[y, x] = bits
    return out


def cost_volume(cl, cr, gl, gr, il, ir, n_disp, lam_s, lam_g, lam_ad):
    h, w = cl.shape
    terms = 1 + (lam_g is not None) + (lam_ad is not None)
    out = np.full((h, w, n_disp), terms, dtype=np.float64)
    for y in range(h):
        for x in range(w):
            for d in range(min(n_disp, x + 1)):
                ham = bin(int(cl[y, x]) ^ int(cr[y, x - d])).count("1")
                c = 1 - np.exp(-ham / lam_s)
                if lam_g is not None:
                    c += 1 - np.exp(-abs(float(gl[y, x]) - float(gr[y, x - d])) / lam_g)
                if lam_ad is not None:
                    ad = np.abs(il[y, x].astype(float) - ir[y, x - d].astype(float)).mean()
                    c += 1 - np.exp(-ad / lam_ad)
                out[y, x, d] = c
    return out


def cross_arms(image, theta, grad, tau1, tau2, tau3, l1, l2, kappa, g_sat):
    h, w = theta.shape
    img = image.astype(float).reshape(h, w, -1)

    def dist(a, b):
        return np.abs(img[a] - img[b]).max()

    out = np.zeros((h, w, 4), dtype=int)
    for y in range(h):
        for x in range(w):
            s = min(1.0, grad[y, x] / g_sat)
            for k, (sy, sx, phi) in enumerate(((0, -1, 0.0), (0, 1, 0.0),
                                               (-1, 0, np.pi / 2), (1, 0, np.pi / 2))):
                f = max(0.0, 1 + kappa * abs(np.cos(theta[y, x] - phi)) * s)
                n = 0
                while n < l2:
                    ny, nx = y + (n + 1) * sy, x + (n + 1) * sx
                    if not (0 <= ny < h and 0 <= nx < w):
                        break
                    to_anchor = dist((ny, nx), (y, x))
                    if to_anchor >= tau1 * f or dist((ny, nx), (ny - sy, nx - sx)) >= tau2:
                        break
                    if n + 1 > l1 and to_anchor >= tau3 * f:
                        break
                    n += 1
                out[y, x, k] = n
    return out


def _combined(arms_l, arms_r, y, x, d, k):
    a = arms_l[y, x, k]
    return min(a, arms_r[y, x - d, k]) if x - d >= 0 else a


def aggregate(volume, arms_l, arms_r, iterations):
    """Average over the explicit set of pixels of each cross region."""
    cur = volume.astype(np.float64)
    h, w, n = cur.shape
    for it in range(iterations):
        rows_first = it % 2 == 0
        nxt = np.zeros_like(cur)
        for y in range(h):
            for x in range(w):
                for d in range(n):
                    def a(yy, xx, k, d=d):
                        return _combined(arms_l, arms_r, yy, xx, d, k)

                    pixels = []
                    if rows_first:  # vertical arm of p, each with its horizontal arm
                        for yy in range(y - a(y, x, 2), y + a(y, x, 3) + 1):
                            pixels += [(yy, xx) for xx in
                                       range(x - a(yy, x, 0), x + a(yy, x, 1) + 1)]
                    else:
                        for xx in range(x - a(y, x, 0), x + a(y, x, 1) + 1):
                            pixels += [(yy, xx) for yy in
                                       range(y - a(y, xx, 2), y + a(y, xx, 3) + 1)]
                    nxt[y, x, d] = np.mean([cur[q][d] for q in pixels])
        cur = nxt
    return cur


def wta_right(volume):
    h, w, n = volume.shape
    out = np.zeros((h, w), dtype=int)
    for y in range(h):
        for x in range(w):
            costs = [volume[y, x + d, d] for d in range(min(n, w - x))]
            out[y, x] = int(np.argmin(costs))
    return out


def lr_labels(dl, dr, n_disp, tol):
    h, w = dl.shape
    out = np.zeros((h, w), dtype=np.uint8)
    for y in range(h):
        for x in range(w):
            d = dl[y, x]
            if d < 0:  # no candidate in the pixel's band
                out[y, x] = 1
                continue
            if x - d >= 0 and abs(d - dr[y, x - d]) <= tol:
                continue
            passes = any(abs(dd - dr[y, x - dd]) <= tol for dd in range(min(n_disp, x + 1)))
            out[y, x] = 2 if passes else 1
    return out


def scanline(cost, il, ir, p1, p2, tau, r1, r2, directions=4):
    """Mean of the directional path costs (rows and columns, and with 8 the diagonals),
    written out direction by direction."""
    h, w, n = cost.shape
    il = il.astype(float).reshape(h, w, -1)
    ir = ir.astype(float).reshape(h, w, -1)
    total = np.zeros((h, w, n))
    steps = [(0, 1), (0, -1), (1, 0), (-1, 0)]
    if directions == 8:
        steps += [(1, 1), (-1, -1), (1, -1), (-1, 1)]
    for dy, dx in steps:
        path = np.zeros((h, w, n))
        ys = range(h) if dy >= 0 else range(h - 1, -1, -1)
        xs = range(w) if dx >= 0 else range(w - 1, -1, -1)
        for y in ys:
            for x in xs:
                py, px = y - dy, x - dx
                if not (0 <= py < h and 0 <= px < w):
                    path[y, x] = cost[y, x]
                    continue
                prev = path[py, px]
                m = prev.min()
                cl = np.abs(il[y, x] - il[py, px]).max() >= tau
                for d in range(n):
                    cr = True
                    if x - d >= 0 and px - d >= 0:
                        cr = np.abs(ir[y, x - d] - ir[py, px - d]).max() >= tau
                    div = r2 if (cl and cr) else (r1 if (cl or cr) else 1.0)
                    q1, q2 = p1 / div, p2 / div
                    cands = [prev[d], m + q2]
                    if d > 0:
                        cands.append(prev[d - 1] + q1)
                    if d < n - 1:
                        cands.append(prev[d + 1] + q1)
                    path[y, x, d] = cost[y, x, d] + min(cands) - m
        total += path / directions
    return total


def region_vote_once(disp, labels, arms, n, min_votes, min_share):
    h, w = disp.shape
    out_d, out_l = disp.copy(), labels.copy()
    for y in range(h):
        for x in range(w):
            if labels[y, x] == 0:
                continue
            votes = [disp[yy, xx]
                     for yy in range(y - arms[y, x, 2], y + arms[y, x, 3] + 1)
                     for xx in range(x - arms[yy, x, 0], x + arms[yy, x, 1] + 1)
                     if labels[yy, xx] == 0]
            if len(votes) <= min_votes:
                continue
            counts = np.bincount(votes, minlength=n)
            if counts.max() > min_share * len(votes):
                out_d[y, x], out_l[y, x] = counts.argmax(), 0
    return out_d, out_l


def discontinuity(disp, volume, jump):
    h, w = disp.shape
    out = disp.copy()
    for y in range(h):
        for x in range(w):
            d = disp[y, x]
            if not np.isfinite(d):
                continue
            best = volume[y, x, int(d)]
            for nx in (x - 1, x + 1):
                if 0 <= nx < w and np.isfinite(disp[y, nx]) and abs(disp[y, nx] - d) > jump:
                    if volume[y, x, int(disp[y, nx])] < best:
                        best = volume[y, x, int(disp[y, nx])]
                        out[y, x] = disp[y, nx]
    return out


def subpixel(disp, volume):
    h, w, n = volume.shape
    out = disp.astype(np.float64).copy()
    for y in range(h):
        for x in range(w):
            d = disp[y, x]
            if not np.isfinite(d) or not 0 < int(d) < n - 1:
                continue
            k = int(d)
            c0, c1, c2 = (float(v) for v in volume[y, x, k - 1:k + 2])
            denom = c0 + c2 - 2 * c1
            if denom > 1e-9:
                out[y, x] = k + np.clip((c0 - c2) / (2 * denom), -0.5, 0.5)
    return out


def fill(disp, labels, image, steps_y, steps_x, max_search):
    h, w = disp.shape
    img = image.astype(float).reshape(h, w, -1)
    out = disp.astype(np.float32).copy()
    for y in range(h):
        for x in range(w):
            if labels[y, x] == 0:
                continue
            best, best_score = np.inf, np.inf
            for sy, sx in zip(steps_y, steps_x):
                for step in range(1, max_search + 1):
                    yy, xx = int(np.round(y + step * sy)), int(np.round(x + step * sx))
                    if not (0 <= yy < h and 0 <= xx < w):
                        break
                    if labels[yy, xx] == 0:
                        score = (disp[yy, xx] if labels[y, x] == 1
                                 else np.abs(img[y, x] - img[yy, xx]).max())
                        if score < best_score:
                            best, best_score = disp[yy, xx], score
                        break
            out[y, x] = best
    return out


def plane_moments(disp, weight):
    """The planes' moments of each pixel (H, W, 11) in float32: w (1, u, v, u^2, u v, v^2, d,
    u d, v d, d^2) and 1, u and v from the image centre, w 0 where d is not finite."""
    height, width = disp.shape
    v, u = np.mgrid[0:height, 0:width].astype(np.float32)
    u -= np.float32((width - 1) / 2.0)
    v -= np.float32((height - 1) / 2.0)
    ok = np.isfinite(disp) & (weight > 0)
    w, d = weight.astype(np.float32), disp.astype(np.float32)
    with np.errstate(invalid="ignore"):
        moments = np.stack([w, w * u, w * v, w * u * u, w * u * v, w * v * v, w * d,
                            w * u * d, w * v * d, w * d * d], axis=-1)
    moments = np.where(ok[..., None], moments, np.float32(0))
    return np.concatenate([moments, np.ones_like(moments[..., :1])], axis=-1)


def _arm_sums(values, lo, hi, axis):
    """Along ``axis``: the sum of ``values`` over i - lo .. i + hi, by running sums in
    float64 (each added in turn), as float32."""
    values = np.moveaxis(values, axis, 0).astype(np.float64)
    sums = np.concatenate([np.zeros_like(values[:1]), np.cumsum(values, axis=0)])
    i = np.arange(values.shape[0]).reshape((-1,) + (1,) * (values.ndim - 1))
    lo = np.moveaxis(lo.astype(np.int64), axis, 0)[..., None]
    hi = np.moveaxis(hi.astype(np.int64), axis, 0)[..., None]
    out = (np.take_along_axis(sums, i + hi + 1, axis=0)
           - np.take_along_axis(sums, i - lo, axis=0))
    return np.moveaxis(out, 0, axis).astype(np.float32)


def region_moment_sums(moments, arms):
    """Each pixel's moments summed over its cross region: the horizontal arms (left,
    right) of the pixels on its vertical arm (up, down); rows, then columns."""
    rows = _arm_sums(moments, arms[0], arms[1], axis=1)
    return _arm_sums(rows, arms[2], arms[3], axis=0)


def plane_values(sums, min_weight, min_spread):
    """The solve of vsmatch._kernels.planes.fit_region_planes from the summed moments
    ``sums``, a pixel at a time, its cases as branches."""
    height, width, _ = sums.shape
    cx, cy = (width - 1) / 2.0, (height - 1) / 2.0
    out = np.full((height, width), np.nan, np.float32)
    spread = np.full((height, width), np.nan, np.float32)
    for y in range(height):
        for x in range(width):
            m = sums[y, x].astype(np.float64)
            w = m[0]
            if not w > 0 or w < float(np.float32(min_weight) * sums[y, x, 10]):
                continue
            mu, mv, md = m[1] / w, m[2] / w, m[6] / w
            suu, suv, svv = m[3] / w - mu * mu, m[4] / w - mu * mv, m[5] / w - mv * mv
            sud, svd = m[7] / w - mu * md, m[8] / w - mv * md
            a = b = 0.0
            det = suu * svv - suv * suv
            if suu >= min_spread and svv >= min_spread and det > 1e-6 * suu * svv:
                a = (sud * svv - svd * suv) / det
                b = (svd * suu - sud * suv) / det
            elif suu >= min_spread:
                a = sud / suu
            elif svv >= min_spread:
                b = svd / svv
            out[y, x] = np.float32(md + a * ((x - cx) - mu) + b * ((y - cy) - mv))
            spread[y, x] = np.float32(np.sqrt(max(m[9] / w - md * md - a * sud - b * svd,
                                                  0.0)))
    return out, spread

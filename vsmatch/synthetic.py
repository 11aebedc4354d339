"""A synthetic stereo pair with known disparity, made in code (``vsmatch demo``).

Textured layers at several depths in front of a slanted background plane are rendered
into both views, back to front, so the pair has real occlusions. Each layer's texture is
attached to the surface, so a left pixel and its match show the same texture value.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np


@dataclass(frozen=True)
class SyntheticPair:
    left: np.ndarray  # (H, W, 3) uint8 BGR
    right: np.ndarray
    disparity: np.ndarray  # left view, float32
    nonocc: np.ndarray  # bool: visible in both views
    max_disp: int


def _texture(rng: np.random.Generator, height: int, width: int) -> np.ndarray:
    """Smooth random colour texture, float32 (H, W, 3) in 0..255."""
    noise = rng.random((height, width, 3), dtype=np.float32)
    tex = cv2.GaussianBlur(noise, (0, 0), 1.2)
    tex = (tex - tex.min()) / max(float(tex.max() - tex.min()), 1e-6)
    base = rng.uniform(40, 200, size=3).astype(np.float32)
    return np.clip(base + (tex - 0.5) * 160.0, 0, 255).astype(np.float32)


def make_pair(width: int = 320, height: int = 240, seed: int = 0) -> SyntheticPair:
    """Render the pair. Layers (back to front): a slanted plane, two rectangles, a disc."""
    rng = np.random.default_rng(seed)
    # (kind, shape in left-view coordinates, disparity a + b * x)
    layers = [
        ("all", None, (6.0, 10.0 / width)),
        ("rect", (0.15 * width, 0.15 * height, 0.5 * width, 0.6 * height), (20.0, 0.0)),
        ("rect", (0.55 * width, 0.1 * height, 0.85 * width, 0.45 * height), (28.0, 0.0)),
        ("disc", (0.4 * width, 0.7 * height, 0.17 * height), (36.0, 0.0)),
    ]
    max_disp = 40
    tex_width = width + 2 * max_disp
    textures = [_texture(rng, height, tex_width) for _ in layers]
    ys, xs = np.mgrid[0:height, 0:width].astype(np.float32)

    views, ids, disparity = [], [], None
    for view in ("left", "right"):
        image = np.zeros((height, width, 3), np.float32)
        layer_id = np.full((height, width), -1, np.int32)
        disp = np.zeros((height, width), np.float32)
        for k, ((kind, shape, (a, b)), tex) in enumerate(zip(layers, textures)):
            # u: the left-view column of the surface point seen at (y, x).
            u = xs if view == "left" else (xs + a) / (1.0 - b)
            inside = _inside(kind, shape, u, ys)
            sample = cv2.remap(tex, u + max_disp, ys, cv2.INTER_LINEAR,
                               borderMode=cv2.BORDER_REFLECT)
            image[inside] = sample[inside]
            layer_id[inside] = k
            disp[inside] = (a + b * u)[inside]
        views.append(np.clip(np.round(image), 0, 255).astype(np.uint8))
        ids.append(layer_id)
        if view == "left":
            disparity = disp
    xr = np.round(xs - disparity).astype(np.int64)
    seen = xr >= 0
    nonocc = np.zeros((height, width), bool)
    yy, xx = np.nonzero(seen)
    nonocc[yy, xx] = ids[1][yy, xr[yy, xx]] == ids[0][yy, xx]
    return SyntheticPair(views[0], views[1], disparity.astype(np.float32), nonocc, max_disp)


def _inside(kind: str, shape, u: np.ndarray, ys: np.ndarray) -> np.ndarray:
    if kind == "all":
        return np.ones(u.shape, bool)
    if kind == "rect":
        x0, y0, x1, y1 = shape
        return (u >= x0) & (u < x1) & (ys >= y0) & (ys < y1)
    cx, cy, r = shape
    return (u - cx) ** 2 + (ys - cy) ** 2 < r * r


def fins_pair(period: int = 12, width: int = 480, height: int = 360, wall: float = 30.0,
              fins: float = 42.0, noise: float = 1.0, seed: int = 0) -> SyntheticPair:
    """Repeated texture: a panel of vertical fins (bright and dark stripes of ``period``
    px, like a radiator's) at disparity ``fins`` in front of a randomly textured wall at
    ``wall``, grey, each view with its own sensor noise of ``noise`` grey levels. Every
    fin pixel matches as well a period away; the panel's edges alone tell which."""
    rng = np.random.default_rng(seed)
    margin = int(np.ceil(max(wall, fins))) + 1
    columns = np.arange(width + 2 * margin, dtype=np.float32) - margin  # surface u
    texture = cv2.GaussianBlur(rng.random((height, columns.size), dtype=np.float32),
                               (0, 0), 1.2)
    texture = 60 + 150 * (texture - texture.min()) / float(texture.max() - texture.min())
    stripes = np.where((columns % period) < period / 2, 190.0, 70.0).astype(np.float32)
    stripes = cv2.GaussianBlur(np.repeat(stripes[None, :], height, 0), (0, 0), 0.7)
    stripes *= (0.9 + 0.1 * np.linspace(0, 1, height, dtype=np.float32))[:, None]  # shading
    x0, x1 = int(0.25 * width), int(0.75 * width)
    rows = slice(int(0.2 * height), int(0.8 * height))
    xs = np.arange(width, dtype=np.float32)
    views = []
    for shift in (0.0, 1.0):  # left view, right view: a point at u shows at x = u - shift d
        image = np.stack([np.interp(xs + shift * wall, columns, row) for row in texture])
        u = xs + shift * fins
        panel = (u >= x0) & (u < x1)
        image[rows, panel] = np.stack([np.interp(u, columns, row)
                                       for row in stripes[rows]])[:, panel]
        image += rng.normal(0.0, noise, image.shape)
        views.append(np.clip(np.round(image), 0, 255).astype(np.uint8))
    disparity = np.full((height, width), wall, np.float32)
    disparity[rows, x0:x1] = fins
    nonocc = xs[None, :] >= disparity  # its match inside the right view
    hidden = (xs >= x0 - (fins - wall)) & (xs < x0)  # wall the panel hides from the right
    nonocc[rows, hidden] = False
    return SyntheticPair(views[0], views[1], disparity, nonocc, int(np.ceil(max(wall, fins))) + 16)


def _wall_and_wire_textures(rng: np.random.Generator, height: int, width: int,
                            wall_contrast: float) -> tuple[np.ndarray, np.ndarray]:
    """A wall's grey texture (110 up, spanning ``wall_contrast`` levels) and a wire's
    (200-240), float32 (H, W), random and smooth."""
    texture, wire_texture = (
        cv2.GaussianBlur(rng.random((height, width), dtype=np.float32), (0, 0), blur)
        for blur in (1.2, 1.0))
    texture = 110 + wall_contrast * (texture - texture.min()) / float(texture.max()
                                                                    - texture.min())
    wire_texture = 200 + 40 * ((wire_texture - wire_texture.min())
                               / float(wire_texture.max() - wire_texture.min()))
    return texture, wire_texture


def _wall_behind_wires(texture: np.ndarray, wire_texture: np.ndarray, columns: np.ndarray,
                       on: np.ndarray, margin: int, wall: float, wires: float, noise: float,
                       rng: np.random.Generator) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """The left and right views (uint8, each with its own sensor noise of ``noise``) of a
    wall at disparity ``wall`` behind wires at ``wires``, both textured along the surface
    coordinate ``columns`` (``margin`` of them left of the views), the wires where ``on``
    (H, columns) holds; and where each view shows a wire."""
    width = columns.size - 2 * margin
    xs = np.arange(width, dtype=np.float32)
    views, shown_on = [], []
    for shift in (0.0, 1.0):  # left view, right view: a point at u shows at x = u - shift d
        image = np.stack([np.interp(xs + shift * wall, columns, row) for row in texture])
        u = xs + shift * wires
        shown = on[:, np.clip(np.floor(u + margin).astype(int), 0, columns.size - 1)]
        fence = np.stack([np.interp(u, columns, row) for row in wire_texture])
        image[shown] = fence[shown]
        image += rng.normal(0.0, noise, image.shape)
        views.append(np.clip(np.round(image), 0, 255).astype(np.uint8))
        shown_on.append(shown)
    return views, shown_on


def wires_pair(thickness: int = 3, spacing: int = 40, width: int = 480, height: int = 360,
               wall: float = 20.0, wires: float = 40.0, noise: float = 1.0,
               seed: int = 0) -> SyntheticPair:
    """Thin structures: vertical wires ``thickness`` px wide every ``spacing`` px, bright
    and finely textured, at disparity ``wires`` in front of a randomly textured wall at
    ``wall`` (grey, each view with its own sensor noise of ``noise`` grey levels). A
    matcher that fattens them draws them wider than ``thickness``."""
    rng = np.random.default_rng(seed)
    margin = int(np.ceil(max(wall, wires))) + 2
    columns = np.arange(width + 2 * margin, dtype=np.float32) - margin  # surface u
    texture, wire_texture = _wall_and_wire_textures(rng, height, columns.size, 30)
    on = (((columns - 20) % spacing) < thickness) & (columns >= 60) & (columns < width - 40)
    views, shown = _wall_behind_wires(texture, wire_texture, columns, np.broadcast_to(
        on, (height, columns.size)), margin, wall, wires, noise, rng)
    disparity = np.where(shown[0], wires, wall).astype(np.float32)
    nonocc = np.arange(width, dtype=np.float32)[None, :] >= disparity
    return SyntheticPair(views[0], views[1], disparity, nonocc,
                         int(np.ceil(max(wall, wires))) + 24)


def fence_pair(thickness: int = 3, spacing: int = 32, width: int = 480, height: int = 360,
               wall: float = 20.0, wires: float = 40.0, wall_contrast: float = 30.0,
               noise: float = 1.0, seed: int = 0) -> SyntheticPair:
    """A chain-link fence: two sets of wires ``thickness`` px wide, at +45 and -45 degrees,
    ``spacing`` px apart (along the rows: diamond holes), bright and finely textured, at
    disparity ``wires`` in front of a wall at ``wall`` whose random texture spans
    ``wall_contrast`` grey levels (grey, each view with its own sensor noise of ``noise``).
    Where :func:`wires_pair`'s vertical wires leave wide gaps along the rows, here every
    row and column crosses a wire at least every ``spacing`` px, and the wires cross."""
    rng = np.random.default_rng(seed)
    margin = int(np.ceil(max(wall, wires))) + 2
    columns = np.arange(width + 2 * margin, dtype=np.float32) - margin  # surface u
    texture, wire_texture = _wall_and_wire_textures(rng, height, columns.size,
                                                    wall_contrast)
    ys = np.arange(height, dtype=np.float32)[:, None]
    along = np.float32(np.sqrt(0.5))  # the wires' distance across, per pixel along a row
    on = ((((columns + ys) * along) % (spacing * along)) < thickness) | \
        ((((columns - ys) * along) % (spacing * along)) < thickness)
    on &= (columns >= 60) & (columns < width - 40)
    views, shown = _wall_behind_wires(texture, wire_texture, columns, on, margin, wall, wires,
                                      noise, rng)
    wire = shown[0]
    disparity = np.where(wire, wires, wall).astype(np.float32)
    # A wall pixel is seen by the right view unless a wire stands in front of its match.
    xs = np.arange(width, dtype=np.float32)
    match = np.clip(np.rint(xs - wall).astype(int), 0, width - 1)
    nonocc = (xs[None, :] >= disparity) & (wire | ~shown[1][:, match])
    return SyntheticPair(views[0], views[1], disparity, nonocc,
                         int(np.ceil(max(wall, wires))) + 24)


def darkened(view: np.ndarray, gain: float, sigma: float, seed: int,
             gamma: float = 1.0) -> np.ndarray:
    """``view`` with its grey levels raised to ``gamma`` (as fractions of 255), scaled by
    ``gain``, and its own sensor noise of ``sigma`` grey levels (seeded by ``seed``), as an
    unlit scene or a short exposure records it: the noise does not shrink with the light."""
    noise = np.random.default_rng(seed).normal(0.0, sigma, view.shape)
    levels = view if gamma == 1.0 else 255.0 * (view / 255.0) ** gamma
    return np.clip(np.rint(levels * gain + noise), 0, 255).astype(np.uint8)


def shadowed(left: np.ndarray, right: np.ndarray, ground_truth: np.ndarray,
             gain: float = 0.12, sigma: float = 1.0
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A real pair with the lower half of the left view's left quarter in deep shadow: its
    grey levels scaled by ``gain`` there, and at the same scene points of the right view
    (found by ``ground_truth``, the left view's disparity; a pixel's neighbours too), then
    both views given their own sensor noise of ``sigma``. Returns the two views and the
    shadowed region of the left view."""
    height, width = left.shape[:2]
    region = np.zeros((height, width), bool)
    region[height // 2:, :width // 4] = True
    left, right = (v.astype(np.float32) for v in (left, right))
    left[region] *= gain
    known = np.nan_to_num(ground_truth, posinf=0) > 0
    ys, xs = np.nonzero(region & known)
    columns = np.rint(xs - ground_truth[ys, xs]).astype(int)
    inside = columns >= 0
    seen = np.zeros(region.shape, np.uint8)
    seen[ys[inside], columns[inside]] = 1
    right[cv2.dilate(seen, np.ones((3, 3), np.uint8)).astype(bool)] *= gain
    return darkened(left, 1.0, sigma, 1), darkened(right, 1.0, sigma, 2), region

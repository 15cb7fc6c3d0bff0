"""Rasterizer: exact coverage (top-left rule), depth test, clipping, perspective-correct (s, t)."""

import numpy as np
import pytest

from vqtex.golden.render.camera import Camera
from vqtex.golden.render.raster import SUBPIXEL_BITS, rasterize, rasterize_screen, snap

ONE = 1 << SUBPIXEL_BITS


def _hits(tris, w, h):
    t, x, y = rasterize_screen(np.asarray(tris, float), w, h)
    cnt = np.zeros((h, w), int)
    np.add.at(cnt, (y, x), 1)
    return cnt


def _strictly_inside(poly_fx, w, h):
    """Pixel centres strictly inside a convex polygon given in fixed point (exact integers)."""
    yy, xx = np.mgrid[0:h, 0:w]
    cx, cy = xx * ONE + ONE // 2, yy * ONE + ONE // 2
    n = len(poly_fx)
    e = [poly_fx[(k + 1) % n] - poly_fx[k] for k in range(n)]
    sgn = np.sign(e[0][0] * e[1][1] - e[0][1] * e[1][0])
    inside = np.ones((h, w), bool)
    for k in range(n):
        a, b = poly_fx[k], poly_fx[(k + 1) % n]
        E = (b[0] - a[0]) * (cy - a[1]) - (b[1] - a[1]) * (cx - a[0])
        inside &= sgn * E > 0
    return inside


def _convex_quads(rng, count, w, h):
    out = []
    while len(out) < count:
        c = rng.uniform(-5, max(w, h) + 5, 2)
        ang = np.sort(rng.uniform(0, 2 * np.pi, 4))
        r = rng.uniform(2, 40, 4)
        p = c + np.stack([r * np.cos(ang), r * np.sin(ang)], 1)
        k = len(out) % 3
        if k == 0:
            p = np.round(p * 2) / 2  # vertices on half pixels: many centres exactly on edges
        elif k == 1:
            p = np.round(p) + 0.5  # vertices on pixel centres
        q = snap(p)
        e = [q[(i + 1) % 4] - q[i] for i in range(4)]
        cr = [e[i][0] * e[(i + 1) % 4][1] - e[i][1] * e[(i + 1) % 4][0] for i in range(4)]
        if all(x > 0 for x in cr) or all(x < 0 for x in cr):
            out.append(p)
    return out


def test_shared_edge_quads_cover_every_pixel_exactly_once():
    rng = np.random.default_rng(1996)
    w, h = 64, 48
    for p in _convex_quads(rng, 300, w, h):
        for diag in (0, 1):  # both diagonals
            a, b, c, d = np.roll(p, -diag, axis=0)
            cnt = _hits([[a, b, c], [a, c, d]], w, h)
            assert cnt.max() <= 1, "a pixel was drawn twice"
            inside = _strictly_inside(snap(np.roll(p, -diag, axis=0)), w, h)
            assert (cnt[inside] == 1).all(), "a gap inside the quad"


def test_full_screen_and_fan_cover_exactly_once():
    w, h = 40, 30
    cnt = _hits([[[0, 0], [w, 0], [w, h]], [[0, 0], [w, h], [0, h]]], w, h)
    assert (cnt == 1).all()
    # a fan of 12 triangles around an interior vertex that sits exactly on a pixel centre
    c = np.array([20.5, 15.5])
    ring = [(0, 0), (10, 0), (20.5, 0), (40, 0), (40, 15.5), (40, 30), (20.5, 30), (0, 30), (0, 15.5), (0, 0)]
    tris = [[c, ring[k], ring[k + 1]] for k in range(len(ring) - 1)]
    cnt = _hits(tris, w, h)
    assert (cnt == 1).all()


def test_winding_does_not_matter_and_degenerate_draws_nothing():
    rng = np.random.default_rng(3)
    for _ in range(50):
        p = rng.uniform(0, 32, (3, 2))
        assert (_hits([p], 32, 32) == _hits([p[::-1]], 32, 32)).all()
    assert _hits([[[1, 1], [10, 10], [20, 20]]], 32, 32).sum() == 0


def test_top_left_rule_on_axis_aligned_square():
    # square [2, 6) x [3, 7) in pixels: its centres are x in 2..5, y in 3..6 -> exactly 16 pixels
    sq = np.array([[2, 3], [6, 3], [6, 7], [2, 7]], float)
    cnt = _hits([[sq[0], sq[1], sq[2]], [sq[0], sq[2], sq[3]]], 10, 10)
    assert cnt.sum() == 16 and (cnt[3:7, 2:6] == 1).all()
    # a centre exactly on the left edge is in, on the right edge out
    sq = np.array([[2.5, 3], [5.5, 3], [5.5, 7], [2.5, 7]], float)
    cnt = _hits([[sq[0], sq[1], sq[2]], [sq[0], sq[2], sq[3]]], 10, 10)
    assert (cnt[3:7, 2:5] == 1).all() and cnt.sum() == 12


def _clip_of(points, cam, w, h):
    vp = cam.view_projection(w, h)
    p = np.concatenate([points, np.ones((len(points), 1))], 1) @ vp.T
    return p


def _raycast_st(cam, w, h, verts, st, px, py):
    """Float reference: intersect the pixel-centre ray with the triangle, interpolate (s, t) in 3D."""
    view = cam.view()
    ndc_x = (px + 0.5) / (w / 2) - 1
    ndc_y = 1 - (py + 0.5) / (h / 2)
    f = 1 / np.tan(np.radians(cam.fov) / 2)
    d_eye = np.stack([ndc_x * (w / h) / f, ndc_y / f, -np.ones_like(ndc_x)], -1)
    d = d_eye @ view[:3, :3]  # eye -> world directions (rows times the rotation's transpose)
    o = np.asarray(cam.position, float)
    v0, v1, v2 = verts
    e1, e2 = v1 - v0, v2 - v0
    # Moller-Trumbore, vectorised over rays
    pvec = np.cross(d, e2)
    det = pvec @ e1
    tvec = o - v0
    u = (pvec @ tvec) / det
    qvec = np.cross(tvec, e1)
    v = (d @ qvec) / det
    return (1 - u - v)[:, None] * st[0] + u[:, None] * st[1] + v[:, None] * st[2]


def test_perspective_correct_interpolation_matches_ray_casting():
    rng = np.random.default_rng(7)
    w, h = 96, 72
    cam = Camera((0.3, 1.2, 3.0), (0.0, 0.0, -2.0), fov=50)
    for _ in range(20):
        verts = rng.uniform([-3, -2, -9], [3, 2, -0.5], (3, 3))
        st = rng.uniform(-2, 3, (3, 2))
        frags = rasterize(_clip_of(verts, cam, w, h)[None], st[None], np.zeros(1, int), w, h, cam.near)
        if len(frags) < 5:
            continue
        py, px = np.divmod(frags.pixel, w)
        ref = _raycast_st(cam, w, h, verts, st, px.astype(float), py.astype(float))
        # vertices are snapped to 1/256 pixel, so allow the (s, t) change of a 1/256-pixel shift
        grad = np.abs(np.stack([frags.dsdx, frags.dsdy, frags.dtdx, frags.dtdy])).max(0)
        tol = 1e-9 + grad * (2.0 / ONE) + 1e-6
        assert (np.abs(frags.s - ref[:, 0]) <= tol).all()
        assert (np.abs(frags.t - ref[:, 1]) <= tol).all()


def test_screen_barycentric_formula_and_derivatives():
    """Against the textbook formula on the snapped vertices: s = sum(l_i s_i / w_i) / sum(l_i / w_i)."""
    rng = np.random.default_rng(11)
    w, h = 80, 60
    cam = Camera((0.0, 0.5, 2.0), (0.0, 0.0, -5.0), fov=60)
    for _ in range(20):
        verts = rng.uniform([-4, -3, -12], [4, 3, -1], (3, 3))
        st = rng.uniform(0, 4, (3, 2))
        clip = _clip_of(verts, cam, w, h)
        frags = rasterize(clip[None], st[None], np.zeros(1, int), w, h, cam.near)
        if len(frags) < 5:
            continue
        sx = (clip[:, 0] / clip[:, 3] + 1) * w / 2
        sy = (1 - clip[:, 1] / clip[:, 3]) * h / 2
        P = snap(np.stack([sx, sy], 1)) / ONE

        def ref(x, y):
            def area(a, b, px, py):
                return (b[0] - a[0]) * (py - a[1]) - (b[1] - a[1]) * (px - a[0])
            l0, l1, l2 = area(P[1], P[2], x, y), area(P[2], P[0], x, y), area(P[0], P[1], x, y)
            qs = np.stack([l0, l1, l2], -1) / clip[:, 3]
            return (qs @ st) / qs.sum(-1, keepdims=True)

        py, px = np.divmod(frags.pixel, w)
        x, y = px + 0.5, py + 0.5
        r = ref(x, y)
        assert np.allclose(frags.s, r[:, 0], atol=1e-9, rtol=1e-9)
        assert np.allclose(frags.t, r[:, 1], atol=1e-9, rtol=1e-9)
        e = 1e-4
        dsdx = (ref(x + e, y) - ref(x - e, y)) / (2 * e)
        dsdy = (ref(x, y + e) - ref(x, y - e)) / (2 * e)
        assert np.allclose(frags.dsdx, dsdx[:, 0], atol=1e-5, rtol=1e-5)
        assert np.allclose(frags.dtdx, dsdx[:, 1], atol=1e-5, rtol=1e-5)
        assert np.allclose(frags.dsdy, dsdy[:, 0], atol=1e-5, rtol=1e-5)
        assert np.allclose(frags.dtdy, dsdy[:, 1], atol=1e-5, rtol=1e-5)


def test_depth_test_nearest_wins_in_any_order_ties_to_first():
    w, h = 32, 32
    cam = Camera((0, 0, 0), (0, 0, -1), fov=60)

    def quad(z, size):
        v = np.array([[-size, -size, z], [size, -size, z], [size, size, z], [-size, size, z]], float)
        c = _clip_of(v, cam, w, h)
        return np.stack([c[[0, 1, 2]], c[[0, 2, 3]]])

    st = np.zeros((2, 3, 2))
    near, far = quad(-2.0, 0.5), quad(-4.0, 5.0)
    for order in ((near, far, 0), (far, near, 1)):
        clip = np.concatenate(order[:2])
        tex = np.array([order[2]] * 2 + [1 - order[2]] * 2)  # texture 0 = near quad
        f = rasterize(clip, np.concatenate([st, st]), tex, w, h, 0.1)
        assert len(f) == w * h
        centre = f.tex.reshape(h, w)[12:20, 12:20]
        assert (centre == 0).all()
        assert f.tex.reshape(h, w)[0, 0] == 1
    same = quad(-3.0, 5.0)
    f = rasterize(np.concatenate([same, same]), np.zeros((4, 3, 2)), np.array([5, 5, 6, 6]), w, h, 0.1)
    assert (f.tex == 5).all()


def test_clipping_floor_behind_camera_matches_raycast():
    w, h = 64, 48
    cam = Camera((0.0, 1.5, 0.0), (0.0, 1.0, -5.0), fov=60, near=0.1)
    verts = np.array([[-50, 0, 40], [50, 0, 60], [50, 0, -50], [-50, 0, -50]], float)
    st = np.array([[0, 0], [10, 0], [10, 10], [0, 10]], float)
    clip = _clip_of(verts, cam, w, h)
    tris = np.stack([clip[[0, 1, 2]], clip[[0, 2, 3]]])
    sts = np.stack([st[[0, 1, 2]], st[[0, 2, 3]]])
    f = rasterize(tris, sts, np.zeros(2, int), w, h, cam.near)
    py, px = np.divmod(f.pixel, w)
    assert py.min() > 0 and len(f) > w * h // 3  # the floor fills the lower part
    for k, tri in enumerate(([0, 1, 2], [0, 2, 3])):
        sel = f.tri == k
        ref = _raycast_st(cam, w, h, verts[tri], st[tri], px[sel].astype(float), py[sel].astype(float))
        # snapping moves the (clipped) vertices by < 1/256 pixel: allow that shift's (s, t) change
        grad = np.abs(np.stack([f.dsdx, f.dsdy, f.dtdx, f.dtdy])[:, sel]).max(0)
        assert (np.abs(f.s[sel] - ref[:, 0]) <= grad * (2.0 / ONE) + 1e-6).all()
        assert (np.abs(f.t[sel] - ref[:, 1]) <= grad * (2.0 / ONE) + 1e-6).all()
    # the horizon row and everything below is covered without gaps
    cov = np.zeros(w * h, bool)
    cov[f.pixel] = True
    first = py.min()
    assert cov.reshape(h, w)[first + 1:].all()


def test_triangle_entirely_behind_camera_draws_nothing():
    cam = Camera((0, 0, 0), (0, 0, -1))
    v = np.array([[-1, -1, 2], [1, -1, 2], [0, 1, 2]], float)
    f = rasterize(_clip_of(v, cam, 16, 16)[None], np.zeros((1, 3, 2)), np.zeros(1, int), 16, 16, 0.1)
    assert len(f) == 0


@pytest.mark.parametrize("shape", [(17, 9), (1, 1), (64, 3)])
def test_odd_frame_sizes(shape):
    w, h = shape
    cnt = _hits([[[0, 0], [w, 0], [w, h]], [[0, 0], [w, h], [0, h]]], w, h)
    assert (cnt == 1).all()


def test_coverage_does_not_depend_on_the_chunk_size():
    from vqtex.golden.render.raster import coverage

    rng = np.random.default_rng(5)
    tris = snap(rng.uniform(-20, 90, (40, 3, 2)))

    def run(chunk):
        parts = list(coverage(tris, 64, 48, chunk=chunk))
        t, x, y = (np.concatenate(p) for p in zip(*parts))
        return sorted(zip(t.tolist(), x.tolist(), y.tolist()))

    ref = run(1 << 20)
    assert len(ref) > 1000
    assert run(7) == ref and run(64) == ref and run(1000) == ref

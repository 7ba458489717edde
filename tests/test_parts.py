"""Tests of bifilar.parts: primitives, composition, support function,
config validation and the Solar Boat geometric model (thesis sections 3, 8.1).

Independent references used here:
* Gauss-Legendre / trapezoid quadrature of the density over each shape in its
  natural coordinates, mapped to the build frame with scipy's Rotation (not
  the package's rotation code).  The integrands (second moments times the
  Jacobian) are polynomials in the radial / axial / cos(theta) coordinates
  and trigonometric polynomials of degree 2 in the azimuth, and the rules
  used are exact for them, so the quadrature error is pure round-off.
* scipy.integrate.tplquad in Cartesian coordinates (adaptive, its own error
  estimate) for the closed-form moments.
* brute-force point sampling for the support function.
"""

from __future__ import annotations

import math
import warnings
from pathlib import Path

import numpy as np
import pytest
import yaml
from numpy.polynomial.legendre import leggauss
from scipy import integrate
from scipy.spatial.transform import Rotation

from bifilar.errors import InputError
from bifilar.parts import (
    SHAPES,
    Composite,
    Part,
    PartError,
    box,
    composite,
    hollow_cylinder,
    hollow_sphere,
    part_from_dict,
    part_inertia,
    parts_from_list,
    point_mass,
    slender_beam,
    solid_cylinder,
    solid_sphere,
    support,
    transform_part,
)

REPO = Path(__file__).resolve().parents[1]
SOLAR_BOAT = REPO / "configs" / "solar_boat.yaml"

# Round-off allowance for sums of O(1e3) double-precision terms of one sign
# (quadrature, parallel-axis sums, 3x3 rotations): ~1e3 * 2.2e-16 ~ 2e-13;
# 1e-12 relative leaves a factor 5 margin while any formula slip (missing
# factor 1/4, r^2 vs r) is >= 1e-3.
RTOL_ROUNDOFF = 1e-12


# --------------------------------------------------------------------------
# independent helpers


def gauss(n, a, b):
    """Gauss-Legendre nodes and weights on [a, b] (exact for degree 2n-1)."""
    x, w = leggauss(n)
    return 0.5 * (b - a) * x + 0.5 * (b + a), 0.5 * (b - a) * w


def azimuth(n):
    """Trapezoid rule on [0, 2 pi): exact for trig polynomials of degree < n."""
    return np.arange(n) * (2 * np.pi / n), np.full(n, 2 * np.pi / n)


def local_nodes(spec):
    """Quadrature nodes (k, 3) in the part frame (CoM at origin, symmetry
    axis z) and weights (k,) = volume (or length) elements, for a spec dict.

    The integrands of interest are of degree <= 2 in Cartesian coordinates;
    with the Jacobians below they are polynomials of degree <= 4 in r, <= 2 in
    z or cos(theta) and trig degree 2 in phi: 4-5 Gauss points and 8 azimuth
    points integrate them exactly; we use more for a margin."""
    s = spec["shape"]
    if s in ("solid_cylinder", "hollow_cylinder"):
        ro = spec.get("radius", spec.get("outer_radius"))
        ri = spec.get("inner_radius", 0.0)
        r, wr = gauss(6, ri, ro)
        p, wp = azimuth(12)
        z, wz = gauss(4, -spec["length"] / 2, spec["length"] / 2)
        R, P, Z = np.meshgrid(r, p, z, indexing="ij")
        W = np.einsum("i,j,k->ijk", wr * r, wp, wz)  # Jacobian r
        X = np.stack([R * np.cos(P), R * np.sin(P), Z], -1)
    elif s == "box":
        lx, ly, lz = spec["size"]
        gx, gy, gz = (gauss(4, -l / 2, l / 2) for l in (lx, ly, lz))
        X = np.stack(np.meshgrid(gx[0], gy[0], gz[0], indexing="ij"), -1)
        W = np.einsum("i,j,k->ijk", gx[1], gy[1], gz[1])
    elif s in ("solid_sphere", "hollow_sphere"):
        ro = spec.get("radius", spec.get("outer_radius"))
        ri = spec.get("inner_radius", 0.0)
        r, wr = gauss(6, ri, ro)
        u, wu = gauss(6, -1.0, 1.0)  # u = cos(theta)
        p, wp = azimuth(12)
        R, U, P = np.meshgrid(r, u, p, indexing="ij")
        S = np.sqrt(1 - U**2)
        X = np.stack([R * S * np.cos(P), R * S * np.sin(P), R * U], -1)
        W = np.einsum("i,j,k->ijk", wr * r**2, wu, wp)  # Jacobian r^2
    elif s == "slender_beam":
        z, wz = gauss(4, -spec["length"] / 2, spec["length"] / 2)
        X = np.stack([0 * z, 0 * z, z], -1)
        W = wz
    elif s == "point_mass":
        X, W = np.zeros((1, 3)), np.ones(1)
    else:  # pragma: no cover
        raise ValueError(s)
    return X.reshape(-1, 3), W.reshape(-1)


def basis_with_axis(a):
    """A right-handed orthonormal basis (columns) whose third vector is a/|a|,
    by Gram-Schmidt (independent of the package's axis_rotation)."""
    a = np.asarray(a, float) / np.linalg.norm(a)
    helper = np.eye(3)[np.argmin(np.abs(a))]
    e1 = helper - np.dot(helper, a) * a
    e1 /= np.linalg.norm(e1)
    return np.column_stack([e1, np.cross(a, e1), a])


def orientation_of(spec):
    """Part -> build rotation matrix of a spec, computed with scipy."""
    if "axis" in spec:
        return basis_with_axis(spec["axis"])
    if "rotation" in spec:
        return Rotation.from_rotvec(spec["rotation"]).as_matrix()
    return np.eye(3)


def quadrature_mass_properties(spec):
    """(mass, com, inertia about own com in build axes) by direct integration
    of the uniform density m / V over the shape described by ``spec``."""
    X, W = local_nodes(spec)
    R = orientation_of(spec)
    c = np.asarray(spec.get("position", [0, 0, 0]), float)
    pts = c + X @ R.T  # build frame
    rho = spec["mass"] / W.sum()
    m = rho * W.sum()
    com = rho * (W @ pts) / m
    d = pts - com
    I = rho * (np.eye(3) * (W @ np.einsum("ij,ij->i", d, d)) - np.einsum("k,ki,kj->ij", W, d, d))
    return m, com, I


def union_inertia_by_quadrature(specs):
    """Inertia of a union of parts about the union's CoM, integrating every
    part's density directly about that point (no parallel-axis theorem)."""
    pts, wts = [], []
    for spec in specs:
        X, W = local_nodes(spec)
        R = orientation_of(spec)
        pts.append(np.asarray(spec.get("position", [0, 0, 0]), float) + X @ R.T)
        wts.append(W * spec["mass"] / W.sum())  # mass elements
    P, M = np.concatenate(pts), np.concatenate(wts)
    com = M @ P / M.sum()
    d = P - com
    I = np.eye(3) * (M @ np.einsum("ij,ij->i", d, d)) - np.einsum("k,ki,kj->ij", M, d, d)
    return M.sum(), com, I


def random_spec(shape, rng, oriented_by="rotation"):
    """A random, valid config mapping of the given shape."""
    spec = {"shape": shape, "mass": float(rng.uniform(0.5, 20.0)), "position": rng.normal(0, 1, 3).tolist()}
    if shape == "solid_cylinder":
        spec.update(radius=rng.uniform(0.05, 0.5), length=rng.uniform(0.05, 2.0))
    elif shape == "hollow_cylinder":
        ro = rng.uniform(0.1, 0.5)
        spec.update(outer_radius=ro, inner_radius=ro * rng.uniform(0.0, 0.95), length=rng.uniform(0.05, 2.0))
    elif shape == "box":
        spec.update(size=rng.uniform(0.02, 2.0, 3).tolist())
    elif shape == "solid_sphere":
        spec.update(radius=rng.uniform(0.05, 0.6))
    elif shape == "hollow_sphere":
        ro = rng.uniform(0.1, 0.6)
        spec.update(outer_radius=ro, inner_radius=ro * rng.uniform(0.0, 0.95))
    elif shape == "slender_beam":
        spec.update(length=rng.uniform(0.1, 3.0))
    axisym = shape in ("solid_cylinder", "hollow_cylinder", "slender_beam")
    if axisym and oriented_by == "axis":
        spec["axis"] = (rng.normal(0, 1, 3) * rng.uniform(0.1, 10)).tolist()  # not normalised
    elif shape != "point_mass":
        spec["rotation"] = Rotation.random(random_state=rng).as_rotvec().tolist()
    return spec


def rel_err(a, b):
    return np.max(np.abs(np.asarray(a) - np.asarray(b))) / np.max(np.abs(b))


# --------------------------------------------------------------------------
# thesis section 3: the dumbbell


def test_dumbbell_of_section_3():
    # two 10 kg solid cylinders r = 0.10 m, width 0.05 m, symmetry axes along
    # the handle (x), centres 0.06 m from the perpendicular bisector.
    d = [
        solid_cylinder(10.0, 0.10, 0.05, (x, 0.0, 0.0), axis=[1, 0, 0], name=f"weight {x}")
        for x in (-0.06, 0.06)
    ]
    c = composite(d)
    # exact rational result of the thesis; 1e-12 relative = round-off only
    assert c.inertia[2, 2] == pytest.approx(1514 / 12000, rel=RTOL_ROUNDOFF)
    assert c.inertia[1, 1] == pytest.approx(1514 / 12000, rel=RTOL_ROUNDOFF)
    # each weight about its own transverse axis: 13/480 (thesis's I_p*)
    assert part_inertia(d[0])[1, 1] == pytest.approx(13 / 480, rel=RTOL_ROUNDOFF)
    # about the handle: two discs 1/2 m r^2
    assert c.inertia[0, 0] == pytest.approx(2 * 0.5 * 10 * 0.01, rel=RTOL_ROUNDOFF)
    assert c.mass == 20.0
    np.testing.assert_allclose(c.com, 0.0, atol=1e-15)


# --------------------------------------------------------------------------
# every primitive against quadrature of its density


@pytest.mark.parametrize("shape", SHAPES)
@pytest.mark.parametrize("oriented_by", ["rotation", "axis"])
@pytest.mark.parametrize("seed", range(4))
def test_primitive_inertia_matches_quadrature(shape, oriented_by, seed):
    rng = np.random.default_rng(1000 * seed + SHAPES.index(shape))
    spec = random_spec(shape, rng, oriented_by)
    part = part_from_dict(spec, "p")
    m, com, I_ref = quadrature_mass_properties(spec)
    I = part_inertia(part)
    assert part.mass == pytest.approx(m, rel=RTOL_ROUNDOFF)
    np.testing.assert_allclose(part.position, com, atol=1e-12 * (1 + np.abs(com).max()))
    if shape == "point_mass":
        np.testing.assert_array_equal(I, np.zeros((3, 3)))
    else:
        # exact quadrature -> round-off only (see RTOL_ROUNDOFF)
        assert rel_err(I, I_ref) < RTOL_ROUNDOFF
    np.testing.assert_array_equal(I, I.T)


def _cartesian_moments(mass, inside_z_bounds, xy_bounds):
    """Diagonal second-moment integrals (Ixx, Iyy, Izz) of a uniform body by
    scipy tplquad in Cartesian coordinates."""
    opts = dict(epsabs=1e-13, epsrel=1e-11)
    (x0, x1), ylims = xy_bounds
    vol = integrate.tplquad(lambda z, y, x: 1.0, x0, x1, *ylims, *inside_z_bounds, **opts)[0]
    rho = mass / vol
    out = []
    for f in (lambda z, y, x: y * y + z * z, lambda z, y, x: x * x + z * z, lambda z, y, x: x * x + y * y):
        out.append(rho * integrate.tplquad(f, x0, x1, *ylims, *inside_z_bounds, **opts)[0])
    return np.array(out)


def test_closed_forms_against_cartesian_tplquad():
    # solid cylinder r = 0.3, L = 0.8 along z, m = 7: integrate over the disc
    # (x, y) and z in [-L/2, L/2].  tplquad's requested relative accuracy is
    # 1e-11 per integral; 1e-9 covers the ratio of two such integrals.
    r, L, m = 0.3, 0.8, 7.0
    ref = _cartesian_moments(
        m,
        (lambda x, y: -L / 2, lambda x, y: L / 2),
        ((-r, r), (lambda x: -math.sqrt(max(r * r - x * x, 0.0)), lambda x: math.sqrt(max(r * r - x * x, 0.0)))),
    )
    got = np.diag(part_inertia(solid_cylinder(m, r, L)))
    np.testing.assert_allclose(got, ref, rtol=1e-9)

    # solid ball R = 0.4, m = 3
    R, m = 0.4, 3.0

    def zb(sign):
        return lambda x, y: sign * math.sqrt(max(R * R - x * x - y * y, 0.0))

    ref = _cartesian_moments(
        m,
        (zb(-1), zb(1)),
        ((-R, R), (lambda x: -math.sqrt(max(R * R - x * x, 0.0)), lambda x: math.sqrt(max(R * R - x * x, 0.0)))),
    )
    got = np.diag(part_inertia(solid_sphere(m, R)))
    np.testing.assert_allclose(got, ref, rtol=1e-9)


# --------------------------------------------------------------------------
# textbook limits


def test_thin_hollow_cylinder_axial_is_m_r2():
    m, R, L = 2.0, 0.25, 1.0
    eps = 1e-9
    p = hollow_cylinder(m, R, R * (1 - eps), L)  # axis z
    # exact value m (R^2 + r^2)/2 differs from m R^2 by ~ eps relative
    assert part_inertia(p)[2, 2] == pytest.approx(m * R * R, rel=2 * eps)
    # transverse: m (6 R^2 + L^2)/12 in the limit
    assert part_inertia(p)[0, 0] == pytest.approx(m * (6 * R * R + L * L) / 12, rel=2 * eps)


def test_thin_shell_is_two_thirds_m_r2_without_division_by_zero():
    m, R = 1.5, 0.3
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # any 0/0 or overflow RuntimeWarning fails
        with np.errstate(all="raise"):
            thin = part_inertia(hollow_sphere(m, R, R))
            near = part_inertia(hollow_sphere(m, R, R * (1 - 1e-12)))
            mid = part_inertia(hollow_sphere(m, R, R * (1 - 1e-6)))
    np.testing.assert_allclose(np.diag(thin), 2 / 3 * m * R * R, rtol=RTOL_ROUNDOFF)
    # continuity: I/(m R^2) = 2/3 - (1/3)(1-q) + O((1-q)^2), so a gap of
    # 1e-12 (1e-6) changes I by at most ~1e-12 (~1e-6) relative
    np.testing.assert_allclose(np.diag(near), 2 / 3 * m * R * R, rtol=1e-11)
    np.testing.assert_allclose(np.diag(mid), 2 / 3 * m * R * R, rtol=1e-6)
    assert np.all(np.diag(mid) < 2 / 3 * m * R * R)  # thicker shell -> less inertia


def test_hollow_with_zero_inner_radius_equals_solid():
    c_h = hollow_cylinder(3.0, 0.2, 0.0, 0.7, axis=[1, 2, 3])
    c_s = solid_cylinder(3.0, 0.2, 0.7, axis=[1, 2, 3])
    assert rel_err(part_inertia(c_h), part_inertia(c_s)) < 1e-15 * 10  # same formula, few flops
    s_h = hollow_sphere(3.0, 0.2, 0.0)
    s_s = solid_sphere(3.0, 0.2)
    assert rel_err(part_inertia(s_h), part_inertia(s_s)) < 1e-15 * 10
    np.testing.assert_allclose(np.diag(part_inertia(s_s)), 0.4 * 3.0 * 0.04, rtol=RTOL_ROUNDOFF)


def test_slender_limits_of_cylinder_and_box():
    m, L = 4.0, 2.0
    beam = part_inertia(slender_beam(m, L, axis=[0, 0, 1]))
    np.testing.assert_allclose(np.diag(beam), [m * L * L / 12, m * L * L / 12, 0.0], rtol=RTOL_ROUNDOFF, atol=0)
    r = 1e-4
    cyl = part_inertia(solid_cylinder(m, r, L))
    # transverse m(3r^2 + L^2)/12 differs from m L^2/12 by 3 r^2/L^2 = 7.5e-9
    assert cyl[0, 0] == pytest.approx(beam[0, 0], rel=1e-8)
    bx = part_inertia(box(m, [r, r, L]))
    assert bx[0, 0] == pytest.approx(beam[0, 0], rel=1e-8)  # r^2/L^2 = 2.5e-9


def test_box_principal_values_and_plate():
    # thin plate 5 m x 2.5 m, 100 kg (thesis section 7.1 analytical values
    # 260.4167 / 208.333 / 52.0833 ignore the thickness; here 1 mm thick)
    p = part_inertia(box(100.0, [2.5, 5.0, 0.001]))
    # the thickness adds m t^2/12 = 8.3e-6 kg m^2 to two of them and the
    # 7-decimal literals are off by <= 5e-8: 1e-5 kg m^2 absolute covers both
    np.testing.assert_allclose(np.diag(p), [208.3333333, 52.0833333, 260.4166667], rtol=0, atol=1e-5)


# --------------------------------------------------------------------------
# composition: parallel-axis theorem and invariance


def test_single_part_at_offset_is_its_own_inertia():
    rng = np.random.default_rng(7)
    for shape in SHAPES:
        p = part_from_dict(random_spec(shape, rng), "p")
        c = composite([p])
        # (m c)/m may differ from c in the last bit
        np.testing.assert_allclose(c.com, np.array(p.position), rtol=1e-15, atol=1e-300)
        np.testing.assert_allclose(c.inertia, part_inertia(p), rtol=0, atol=1e-15 * (1 + np.abs(c.inertia).max()))
        assert c.mass == p.mass


def test_two_point_masses_reduced_mass():
    m1, m2, d = 2.0, 3.0, 1.7
    c = composite([point_mass(m1, (0, 0, 0)), point_mass(m2, (d, 0, 0))])
    mu = m1 * m2 / (m1 + m2)
    np.testing.assert_allclose(c.com, [m2 * d / (m1 + m2), 0, 0], rtol=RTOL_ROUNDOFF)
    np.testing.assert_allclose(np.diag(c.inertia), [0.0, mu * d * d, mu * d * d], rtol=RTOL_ROUNDOFF, atol=1e-15)


def _rigid(rng):
    """A random rotation matrix (scipy) and translation (m)."""
    return Rotation.random(random_state=rng).as_matrix(), rng.normal(0, 2, 3)


def test_split_bodies_reassemble_exactly():
    """Parallel-axis theorem on exact decompositions, moved rigidly."""
    rng = np.random.default_rng(11)
    for _ in range(3):
        Q, t = _rigid(rng)
        # a box cut into two halves along x
        lx, ly, lz, m = 1.3, 0.7, 0.4, 6.0
        whole = [box(m, [lx, ly, lz])]
        halves = [box(m / 2, [lx / 2, ly, lz], (s * lx / 4, 0, 0)) for s in (-1, 1)]
        # a solid cylinder = tube + core (masses in proportion to the areas)
        R, r, L, mc = 0.4, 0.25, 0.9, 5.0
        core = mc * r * r / (R * R)
        cyl = [solid_cylinder(mc, R, L, axis=[0, 1, 0])]
        cyl_split = [hollow_cylinder(mc - core, R, r, L, axis=[0, 1, 0]), solid_cylinder(core, r, L, axis=[0, 1, 0])]
        # a cylinder cut into two shorter ones along its axis
        cyl_cut = [solid_cylinder(mc / 2, R, L / 2, (0, s * L / 4, 0), axis=[0, 1, 0]) for s in (-1, 1)]
        # a solid ball = shell + core (masses in proportion to the volumes)
        Rs, rs, ms = 0.5, 0.3, 8.0
        sc = ms * (rs / Rs) ** 3
        ball = [solid_sphere(ms, Rs)]
        ball_split = [hollow_sphere(ms - sc, Rs, rs), solid_sphere(sc, rs)]
        for a, b in ((whole, halves), (cyl, cyl_split), (cyl, cyl_cut), (ball, ball_split)):
            a = [transform_part(p, Q, t) for p in a]
            b = [transform_part(p, Q, t) for p in b]
            ca, cb = composite(a), composite(b)
            assert ca.mass == pytest.approx(cb.mass, rel=RTOL_ROUNDOFF)
            np.testing.assert_allclose(ca.com, cb.com, rtol=0, atol=1e-13)
            assert rel_err(cb.inertia, ca.inertia) < RTOL_ROUNDOFF


@pytest.mark.parametrize("seed", range(5))
def test_composite_matches_direct_integration_of_the_union(seed):
    """Parallel-axis theorem vs integrating every part about the union CoM."""
    rng = np.random.default_rng(seed)
    specs = [random_spec(s, rng, rng.choice(["rotation", "axis"])) for s in SHAPES]
    c = composite([part_from_dict(s, f"p{i}") for i, s in enumerate(specs)])
    m, com, I = union_inertia_by_quadrature(specs)
    assert c.mass == pytest.approx(m, rel=RTOL_ROUNDOFF)
    np.testing.assert_allclose(c.com, com, rtol=0, atol=RTOL_ROUNDOFF * np.abs(com).max())
    assert rel_err(c.inertia, I) < RTOL_ROUNDOFF


def _invariants(I):
    return np.array([np.trace(I), 0.5 * (np.trace(I) ** 2 - np.trace(I @ I)), np.linalg.det(I)])


@pytest.mark.parametrize("seed", range(5))
def test_rotation_invariance(seed):
    rng = np.random.default_rng(100 + seed)
    parts = [part_from_dict(random_spec(s, rng, "axis"), "p") for s in SHAPES for _ in range(2)]
    c = composite(parts)
    Q = Rotation.random(random_state=rng).as_matrix()
    t = rng.normal(0, 3, 3)
    moved = composite([transform_part(p, Q, t) for p in parts])
    # tensor transforms as Q I Q^T; CoM moves rigidly; scalar invariants and
    # principal moments are unchanged (round-off of 3x3 products only)
    assert rel_err(moved.inertia, Q @ c.inertia @ Q.T) < RTOL_ROUNDOFF
    np.testing.assert_allclose(moved.com, Q @ c.com + t, rtol=0, atol=1e-12 * (1 + np.abs(t).max()))
    np.testing.assert_allclose(_invariants(moved.inertia), _invariants(c.inertia), rtol=RTOL_ROUNDOFF)
    np.testing.assert_allclose(moved.principal_moments, c.principal_moments, rtol=RTOL_ROUNDOFF)
    # the same with a rotation vector given to transform_part
    rv = rng.normal(0, 1, 3)
    moved2 = composite([transform_part(p, rv) for p in parts])
    Q2 = Rotation.from_rotvec(rv).as_matrix()
    assert rel_err(moved2.inertia, Q2 @ c.inertia @ Q2.T) < RTOL_ROUNDOFF


@pytest.mark.parametrize("seed", range(20))
def test_random_composites_are_physical(seed):
    rng = np.random.default_rng(500 + seed)
    k = int(rng.integers(1, 8))
    shapes = rng.choice([s for s in SHAPES if s not in ("point_mass", "slender_beam")], size=k)
    extra = rng.choice(SHAPES, size=int(rng.integers(0, 4)))
    parts = [part_from_dict(random_spec(str(s), rng, "rotation"), "p") for s in [*shapes, *extra]]
    c = composite(parts)
    I, w, V = c.inertia, c.principal_moments, c.principal_axes
    scale = np.trace(I)
    np.testing.assert_array_equal(I, I.T)  # symmetric by construction
    assert np.all(w > 0)  # positive definite (at least one solid part)
    assert np.all(np.diff(w) >= 0)  # ascending
    # triangle inequality of principal moments (equality only for laminae)
    assert w[0] + w[1] >= w[2] - RTOL_ROUNDOFF * scale
    # right-handed orthonormal principal frame reproducing the tensor
    np.testing.assert_allclose(V.T @ V, np.eye(3), atol=1e-13)
    assert np.linalg.det(V) == pytest.approx(1.0, abs=1e-13)
    np.testing.assert_allclose(V @ np.diag(w) @ V.T, I, atol=RTOL_ROUNDOFF * scale)
    # read-only results: a frozen record
    with pytest.raises(ValueError):
        c.inertia[0, 0] = 1.0
    # inertia_about(com) is the inertia; about another point it grows
    np.testing.assert_array_equal(c.inertia_about(c.com), I)
    J = c.inertia_about(c.com + np.array([0.0, 0.0, 1.0]))
    assert J[0, 0] == pytest.approx(I[0, 0] + c.mass, rel=RTOL_ROUNDOFF)


def test_composite_and_support_reject_empty():
    with pytest.raises(ValueError):
        composite([])
    with pytest.raises(ValueError):
        support([], [0, 0, 1])


# --------------------------------------------------------------------------
# support function


def sampled_points(spec, rng):
    """Points of the shape (build frame) including its boundary, and the
    worst-case gap factor g: max over the shape of x.d minus max over the
    samples is <= g |d| (derived per shape below)."""
    s = spec["shape"]
    interior, _ = local_nodes(spec)  # interior quadrature points
    if s in ("solid_cylinder", "hollow_cylinder"):
        R = spec.get("radius", spec.get("outer_radius"))
        L = spec["length"]
        n = 1440
        p = np.arange(n) * 2 * np.pi / n
        rims = [np.stack([R * np.cos(p), R * np.sin(p), np.full(n, h)], -1) for h in (-L / 2, L / 2)]
        X = np.concatenate([interior, *rims])
        # the maximiser lies on a rim circle; nearest rim sample within pi/n
        # in azimuth -> gap <= R (1 - cos(pi/n)) |d| <= R (pi/n)^2 / 2 |d|
        gap = R * (np.pi / n) ** 2 / 2
    elif s == "box":
        corners = np.array(np.meshgrid(*[[-h / 2, h / 2] for h in spec["size"]], indexing="ij")).reshape(3, -1).T
        X, gap = np.concatenate([interior, corners]), 0.0  # a vertex is a maximiser
    elif s in ("solid_sphere", "hollow_sphere"):
        R = spec.get("radius", spec.get("outer_radius"))
        nt, nph = 241, 480
        t = np.linspace(0, np.pi, nt)
        ph = np.arange(nph) * 2 * np.pi / nph
        T, P = np.meshgrid(t, ph, indexing="ij")
        surf = R * np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], -1).reshape(-1, 3)
        X = np.concatenate([interior, surf])
        # any direction is within dtheta/2 + dphi/2 of a grid direction
        # (move along a meridian, then along a parallel of radius <= 1)
        a = (np.pi / (nt - 1) + 2 * np.pi / nph) / 2
        gap = R * a * a / 2
    elif s == "slender_beam":
        L = spec["length"]
        X, gap = np.concatenate([interior, [[0, 0, -L / 2], [0, 0, L / 2]]]), 0.0
    else:
        X, gap = np.zeros((1, 3)), 0.0
    Rm = orientation_of(spec)
    return np.asarray(spec.get("position", [0, 0, 0]), float) + X @ Rm.T, gap


@pytest.mark.parametrize("shape", SHAPES)
@pytest.mark.parametrize("seed", range(3))
def test_support_against_sampled_points(shape, seed):
    rng = np.random.default_rng(2000 + 10 * seed + SHAPES.index(shape))
    spec = random_spec(shape, rng, "axis" if seed % 2 else "rotation")
    part = part_from_dict(spec, "p")
    X, gap = sampled_points(spec, rng)
    D = rng.normal(0, 1, (200, 3)) * rng.uniform(0.2, 5.0, (200, 1))  # not unit
    D = np.concatenate([D, np.eye(3), -np.eye(3), [orientation_of(spec)[:, 2]]])  # axis-aligned too
    h = support(part, D)
    assert h.shape == (D.shape[0],)
    brute = (X @ D.T).max(axis=0)
    norms = np.linalg.norm(D, axis=1)
    slack = 1e-12 * (1 + np.abs(X).max()) * norms  # round-off of dot products
    assert np.all(h >= brute - slack)  # an upper bound of every point
    assert np.all(h - brute <= gap * norms + slack)  # and attained within the sampling gap


def test_support_of_a_union_and_batch_shapes():
    rng = np.random.default_rng(3)
    parts = [part_from_dict(random_spec(s, rng), "p") for s in SHAPES]
    D = rng.normal(size=(50, 3))
    h = support(parts, D)
    each = np.array([support(p, D) for p in parts])
    np.testing.assert_array_equal(h, each.max(axis=0))
    single = support(parts, D[0])
    assert isinstance(single, float) and single == h[0]
    assert support(parts, D[:1]).shape == (1,)
    with pytest.raises(ValueError):
        support(parts, np.zeros((4, 2)))


def test_support_exact_simple_cases():
    cyl = solid_cylinder(1.0, 0.2, 1.0, (1.0, 2.0, 3.0), axis=[1, 0, 0])
    assert support(cyl, [1, 0, 0]) == pytest.approx(1.5, rel=1e-15)
    assert support(cyl, [0, 0, -1]) == pytest.approx(-2.8, rel=1e-15)  # lowest point z = 2.8
    s = 1 / math.sqrt(2)
    assert support(cyl, [s, 0, s]) == pytest.approx(s * 4 + 0.5 * s + 0.2 * s, rel=1e-14)
    b = box(1.0, [2.0, 4.0, 6.0], rotation=[0, 0, math.pi / 2])  # x_part -> y_build
    assert support(b, [1, 0, 0]) == pytest.approx(2.0, rel=1e-14)
    assert support(b, [0, 1, 0]) == pytest.approx(1.0, rel=1e-14)
    assert support(point_mass(1.0, (0, 0, -5)), [0, 0, -2]) == 10.0


# --------------------------------------------------------------------------
# config validation


GOOD = {"shape": "solid_cylinder", "mass": 10.0, "radius": 0.1, "length": 0.05, "position": [0, 0, 0]}


def _with(base, **changes):
    d = dict(base)
    for k, v in changes.items():
        if v is _DROP:
            d.pop(k)
        else:
            d[k] = v
    return d


_DROP = object()
BOX = {"shape": "box", "mass": 1.0, "size": [1.0, 2.0, 0.1]}
TUBE = {"shape": "hollow_cylinder", "mass": 1.0, "outer_radius": 0.2, "inner_radius": 0.1, "length": 1.0}
SHELL = {"shape": "hollow_sphere", "mass": 1.0, "outer_radius": 0.2, "inner_radius": 0.1}

BAD = [
    # (mapping, exact path, substrings of the message)
    (_with(GOOD, radius=-1), "body.parts.2.radius", ["must be a positive number, got -1"]),
    (_with(GOOD, length=0), "body.parts.2.length", ["positive"]),
    (_with(BOX, size=_DROP), "body.parts.2.size", ["missing"]),
    (_with(BOX, size=[1.0, 2.0]), "body.parts.2.size", ["3 numbers"]),
    (_with(BOX, size=[1.0, -2.0, 0.1]), "body.parts.2.size.1", ["positive", "-2.0"]),
    (_with(GOOD, radus=0.1), "body.parts.2.radus", ["unknown key 'radus'", "did you mean 'radius'"]),
    (_with(GOOD, shape="cylindre"), "body.parts.2.shape", ["unknown shape 'cylindre'", "did you mean 'solid_cylinder'"]),
    (_with(GOOD, shape="plate"), "body.parts.2.shape", ["did you mean 'box'"]),
    (_with(GOOD, shape=_DROP), "body.parts.2.shape", ["missing"]),
    (_with(GOOD, mass=float("nan")), "body.parts.2.mass", ["nan"]),
    (_with(GOOD, mass=_DROP), "body.parts.2.mass", ["missing"]),
    (_with(GOOD, mass=True), "body.parts.2.mass", ["number"]),
    (_with(GOOD, radius="1e-3"), "body.parts.2.radius", ["YAML"]),
    (_with(GOOD, radius=float("inf")), "body.parts.2.radius", ["inf"]),
    (_with(GOOD, axis=[0, 0, 0]), "body.parts.2.axis", ["non-zero"]),
    (_with(GOOD, axis=[0, 1]), "body.parts.2.axis", ["3 numbers"]),
    (_with(GOOD, axis=[1, 0, 0], rotation=[0, 0, 0]), "body.parts.2.axis", ["either axis or rotation"]),
    (_with(GOOD, position=[0, 0, "up"]), "body.parts.2.position.2", ["number", "'up'"]),
    (_with(GOOD, position=[0, float("nan"), 0]), "body.parts.2.position.1", ["nan"]),
    (_with(GOOD, rotation=[0, 0, None]), "body.parts.2.rotation.2", ["number"]),
    (_with(BOX, axis=[1, 0, 0]), "body.parts.2.axis", ["unknown key 'axis'", "rotation"]),
    (_with(TUBE, inner_radius=0.2), "body.parts.2.inner_radius", ["less than outer_radius"]),
    (_with(TUBE, inner_radius=-0.01), "body.parts.2.inner_radius", ["non-negative"]),
    (_with(SHELL, inner_radius=0.25), "body.parts.2.inner_radius", ["outer_radius"]),
    (_with(GOOD, name=3), "body.parts.2.name", ["string"]),
    ([1, 2, 3], "body.parts.2", ["mapping"]),
]


@pytest.mark.parametrize("d,path,fragments", BAD, ids=[f"{i}:{b[1].split('.', 3)[-1]}" for i, b in enumerate(BAD)])
def test_part_from_dict_errors_name_the_exact_path(d, path, fragments):
    with pytest.raises(PartError) as ei:
        part_from_dict(d, "body.parts.2")
    e = ei.value
    assert e.path == path
    assert str(e) == f"{path}: {e.message}"
    for f in fragments:
        assert f in e.message
    assert isinstance(e, InputError) and e.field == path


def test_good_inputs_are_accepted():
    p = part_from_dict(GOOD, "body.parts.0")
    assert isinstance(p, Part) and p.shape == "solid_cylinder" and p.name == "solid_cylinder"
    # thin hollow sphere (inner == outer) is allowed, as is inner = 0
    assert part_from_dict(_with(SHELL, inner_radius=0.2), "x").geometry.inner_radius == 0.2
    assert part_from_dict(_with(TUBE, inner_radius=0), "x").geometry.inner_radius == 0.0
    # axis is normalised; integer-valued YAML numbers accepted
    p = part_from_dict(_with(GOOD, axis=[0, 3, 0], mass=10), "x")
    np.testing.assert_allclose(p.axis, [0, 1, 0], atol=1e-15)
    np.testing.assert_allclose(p.rotation_matrix @ p.rotation_matrix.T, np.eye(3), atol=1e-15)
    # axis along -z is a proper rotation too
    p = part_from_dict(_with(GOOD, axis=[0, 0, -2]), "x")
    np.testing.assert_allclose(p.axis, [0, 0, -1])
    assert np.linalg.det(p.rotation_matrix) == pytest.approx(1.0)
    # default position is the origin
    assert part_from_dict(_with(GOOD, position=_DROP), "x").position == (0.0, 0.0, 0.0)
    # frozen record
    with pytest.raises(AttributeError):
        p.mass = 3.0  # type: ignore[misc]


def test_constructors_validate_with_argument_paths():
    with pytest.raises(PartError) as ei:
        solid_cylinder(-1.0, 0.1, 0.2)
    assert ei.value.path == "mass"
    with pytest.raises(PartError) as ei:
        hollow_sphere(1.0, 0.1, 0.2)
    assert ei.value.path == "inner_radius"
    with pytest.raises(PartError) as ei:
        box(1.0, [1.0, 0.0, 1.0])
    assert ei.value.path == "size.1"


def test_parts_from_list_paths():
    with pytest.raises(PartError) as ei:
        parts_from_list([GOOD, _with(GOOD, radius=-1)], "body.parts")
    assert ei.value.path == "body.parts.1.radius"
    for bad in ([], {"a": GOOD}, "solid_cylinder"):
        with pytest.raises(PartError) as ei:
            parts_from_list(bad, "body.parts")
        assert ei.value.path == "body.parts"
    assert len(parts_from_list([GOOD, BOX])) == 2


# --------------------------------------------------------------------------
# the Solar Boat geometric model (thesis section 8.1)


@pytest.fixture(scope="module")
def boat():
    with open(SOLAR_BOAT) as f:
        cfg = yaml.safe_load(f)
    parts = parts_from_list(cfg["body"]["parts"], "body.parts")
    return cfg, parts, composite(parts)


def test_solar_boat_reproduces_thesis_inertias(boat):
    cfg, parts, c = boat
    assert isinstance(c, Composite)
    I3, I2, I1 = c.principal_moments  # ascending: roll, pitch, torsion
    # thesis: I1 = 317.278 (b1, vertical), I2 = 317.154 (b2, pitch),
    # I3 = 83.143 (b3, along CD); required to 0.01 % (the rounded config
    # reaches ~2e-5)
    assert I1 == pytest.approx(317.278, rel=1e-4)
    assert I2 == pytest.approx(317.154, rel=1e-4)
    assert I3 == pytest.approx(83.143, rel=1e-4)
    # axes: build z = b1, y = b2, x = b3 (CD) -> the tensor is diagonal
    assert c.inertia[2, 2] == pytest.approx(317.278, rel=1e-4)
    assert c.inertia[1, 1] == pytest.approx(317.154, rel=1e-4)
    assert c.inertia[0, 0] == pytest.approx(83.143, rel=1e-4)
    off = c.inertia - np.diag(np.diag(c.inertia))
    assert np.abs(off).max() < 1e-6  # symmetric by construction; 1e-6 kg m^2 as required
    np.testing.assert_allclose(np.abs(np.diag(c.principal_axes)), 1.0, atol=1e-9)
    # CoM 0.205 m below the deck plane (z = 0), on the centre line
    assert c.com[2] == pytest.approx(-0.205, abs=1e-3)
    np.testing.assert_allclose(c.com[:2], 0.0, atol=1e-12)


def test_solar_boat_model_is_the_table_8_1_1_boat(boat):
    cfg, parts, c = boat
    shapes = {p.name: p.shape for p in parts}
    assert shapes == {
        "hull": "hollow_cylinder",
        "solar deck": "box",
        "battery": "solid_sphere",
        "cockpit": "hollow_sphere",
        "additional electronics": "solid_sphere",
        "front wing": "slender_beam",
        "rear wing": "slender_beam",
        "pilot": "solid_cylinder",
    }
    by = {p.name: p for p in parts}
    assert 150.0 <= c.mass <= 200.0
    assert by["pilot"].mass / c.mass == pytest.approx(0.44, abs=0.005)  # "nearly 44 %"
    assert -0.3 < by["pilot"].position[2] < 0.0  # close below the deck
    hull = by["hull"].geometry
    assert 5.0 <= hull.length <= 6.0  # a ~6 m boat
    # the deck's top face is the deck plane z = 0
    deck = by["solar deck"]
    assert support(deck, [0, 0, 1]) == pytest.approx(0.0, abs=1e-12)
    # every part stays in the symmetry plane y = 0
    assert all(p.position[1] == 0.0 for p in parts)


def test_solar_boat_rig_is_configuration_1(boat):
    cfg, parts, c = boat
    assert cfg["gravity"] == 9.81
    assert "ASSUMED" in cfg["name"]
    rig = cfg["rig"]
    assert rig["attachments_frame"] == "parts"
    deck = {p.name: p for p in parts}["solar deck"]
    half = deck.geometry.size[0] / 2
    att = np.array(rig["attachments"], float)
    np.testing.assert_allclose(att, [[-half, 0, 0], [half, 0, 0]], atol=1e-12)  # deck ends, on CD
    anchors = np.array(rig["anchors"], float)
    assert anchors.shape == (2, 3) and np.all(anchors[:, 2] == 0.0)
    assert np.ptp(anchors[:, 0]) >= np.ptp(att[:, 0])  # vertical or outward-leaning wires
    lengths = rig["lengths"]
    assert len(lengths) == 2 and lengths[0] == lengths[1] > 0

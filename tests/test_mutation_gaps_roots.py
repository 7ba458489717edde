"""Tests written to kill surviving mutants of invert's root search and fit
check (``bifilar/estimation/roots.py``, whose fit check is now ``fit_check.py``; see docs/mutation.md).  Expected
values come from independent truths: the generalised least-squares
residual and the estimate's Mahalanobis distance written out with explicit
inverses, the forward model (periods of a tensor chosen here) and the
mirror symmetry of a rig -- never from output of the code under test.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from bifilar.analysis.equilibrium import rest_pose
from bifilar.analysis.modes import linear_modes
from bifilar.estimation import fit_check, roots
from bifilar.estimation.invert import invert
from bifilar.estimation.measurements import Hanging, Measurement, MeasurementSet
from bifilar.estimation.problem import admissible_interval

from conftest import trapezoid
from test_fit_check_inputs import UNC, _closed_form, _ms, _plate, L


def test_input_fit_check_is_the_generalised_least_squares_residual_and_distance(monkeypatch):
    """Kills the whitening of the Jacobian by the upper triangle
    (``solve_triangular(L, Jp, lower=True -> False)``: the diagonal of the
    Cholesky factor only) and any other slip in ``input_fit_check`` where
    the inputs' covariance is not diagonal (the existing tests compare with
    ``sum z^2`` at ``C_x = 0`` only).  The periods' covariance is set here:
    ``C = diag(sigma^2 + amp) + C_x + diag(extra)`` with a full ``C_x``
    (``input_period_covariance`` replaced), amplitude factors ``r != 1``; the
    truths, written out with explicit inverses: ``min_dp (res + J dp)^T C^-1
    (res + J dp) = res^T (C^-1 - C^-1 J (J^T C^-1 J)^-1 J^T C^-1) res``, and
    ``d = (J^T W J)^-1 J^T W res`` (``W = diag(sigma^-2)``, the timing-weighted
    step to the fit) in the metric of its covariance ``G C G^T``."""
    T_t, T_s = _closed_form(L + 1e-3)
    res = invert(_ms(_plate(), (T_t, T_s), UNC["timing"]), solve_for=["Izz"], unc=UNC, ladder=False,
                 method="linear")
    pb = res.problem
    sig = np.array([m.std for m in pb.measurements])
    Cx = np.array([[4.0, 3.0], [3.0, 9.0]]) * sig[:, None] * sig[None, :]
    monkeypatch.setattr(fit_check, "input_period_covariance", lambda pb_, p_, r_=None: Cx.copy())
    amp, extra, r = np.array([0.5, 0.0]) * sig**2, np.array([0.0, 0.25]) * sig**2, np.array([1.02, 0.97])
    for p in (res.values, res.values + 3 * res.std, res.values - 20 * res.std):
        z = (fit_check.labelled_periods(pb, p) - np.array([T_t, T_s])) / sig
        ok, chi2_fit, dist, _ = fit_check.input_fit_check(pb, p, z, r=r, extra_var=extra, amp_var=amp)
        C = np.diag(sig**2 + amp + extra) + Cx
        J = pb.jacobian(p) * r[:, None]
        e = z * sig
        Ci = np.linalg.inv(C)
        gls = e @ (Ci - Ci @ J @ np.linalg.inv(J.T @ Ci @ J) @ J.T @ Ci) @ e
        W = np.diag(sig**-2.0)
        Gm = np.linalg.inv(J.T @ W @ J) @ J.T @ W
        d = Gm @ e
        maha = d @ np.linalg.inv(Gm @ C @ Gm.T) @ d
        assert chi2_fit == pytest.approx(gls, rel=1e-9, abs=1e-12)
        assert dist == pytest.approx(maha, rel=1e-9, abs=1e-12)
        assert ok is bool(gls <= 10.828 and maha <= 10.828)  # chi2(1) 99.9 % quantile (K - P = P = 1)


def test_a_product_root_in_the_last_cell_next_to_an_open_end_is_found():
    """Roots next to the open ends of a product's interval (the grid's
    ends are stepped 1e-7 of the width inside: a singular tensor has no
    modes).  Written for the mutants of that inset (``hi - 1e-7 w -> +``,
    ``eigvalsh[0] -> [1]``, ``1e-12 * tr -> / tr``); it does not kill them:
    the modes of a tensor 1e-7 w beyond the end still compute here (see
    docs/mutation.md), but it checks what the inset is for.  The thin plate
    (Izz = Ixx + Iyy) has an Ixy interval open at both ends (Ixy^2 < Ixx
    Iyy); its pitch period at Ixy = 0.99 of the end (forward model, a
    tensor chosen here) has a root in the last and, by the rig's mirror
    (+Ixy and -Ixy give the same periods), one in the first cell."""
    s = trapezoid(h=0.5)
    lo, hi = admissible_interval(s.inertia, "Ixy")
    assert lo == pytest.approx(-np.sqrt(s.inertia[0, 0] * s.inertia[1, 1]), rel=1e-9) and hi == pytest.approx(-lo)
    x = 0.99 * hi
    I = s.inertia.copy()
    I[0, 1] = I[1, 0] = x
    T = linear_modes(replace(s, inertia=I), rest_pose(s)).get("pitch").period
    ms = MeasurementSet([Hanging("h", s, np.eye(3))], [Measurement("pitch", float(T), 1e-4, "period", "--period")])
    res = invert(ms, solve_for=["Ixy"], ladder=False, method="linear")
    got = sorted(r["inertia"]["Ixy"]["value"] for r in res.roots)
    assert got == pytest.approx([-x, x], rel=1e-8)


def test_two_roots_of_a_product_inside_one_grid_cell_are_both_found():
    """Kills ``self.diagonal = i == j -> !=`` (a product of inertia then
    skips the search for a period that turns back inside a grid cell, and a
    diagonal component does it needlessly): the tilted bifilar R2 of
    test_invert_roots has a swing-y period with an interior extremum in Ixz
    near 0.1926 kg m^2, 0.65 of the way through a cell of the 41-point grid;
    a period just short of the extremum is reached at two values 0.002 kg m^2
    either side, one cell, no sign change between grid points.  Truth: the
    forward model (linear modes of each tensor) -- the extremum located by a
    bounded scalar search, the two roots by Brent's method on either side of
    it, the others by an independent 201-point scan."""
    from scipy.optimize import brentq, minimize_scalar

    from bifilar.config import scene_from_dict
    from test_invert_roots import R2

    s = scene_from_dict(R2, warn=False)
    rest = rest_pose(s)
    lo, hi = admissible_interval(s.inertia, "Ixz")

    def T(x):
        I = s.inertia.copy()
        I[0, 2] = I[2, 0] = x
        return linear_modes(replace(s, inertia=I), rest).get("swing-y").period

    sgn = 1.0 if T(0.1926) > T(0.17) else -1.0  # a maximum or a minimum
    top = minimize_scalar(lambda x: -sgn * T(x), bounds=(0.17, 0.21), method="bounded", options={"xatol": 1e-10}).x
    assert 0.175 < top < 0.205  # inside
    cell = (hi - lo) / 40
    target = T(top + 0.1 * cell)
    near = [brentq(lambda x: T(x) - target, top - cell, top, xtol=1e-14),
            brentq(lambda x: T(x) - target, top, top + cell, xtol=1e-14)]
    grid = np.linspace(lo, hi, 41)
    assert not np.any((grid > near[0]) & (grid < near[1]))  # one cell: no grid point between them
    xs = np.linspace(lo + 1e-6 * (hi - lo), hi - 1e-6 * (hi - lo), 201)
    f = np.array([T(x) for x in xs]) - target
    far = [brentq(lambda x: T(x) - target, a, b, xtol=1e-14)
           for a, b, fa, fb in zip(xs, xs[1:], f, f[1:]) if fa * fb < 0 and not (b > top - cell and a < top + cell)]
    ms = MeasurementSet([Hanging("h", s, np.eye(3))], [Measurement("swing-y", float(target), 1e-4, "period",
                                                                     "--period")])
    res = invert(ms, solve_for=["Ixz"], ladder=False, method="linear")
    got = sorted(r["inertia"]["Ixz"]["value"] for r in res.roots)
    assert got == pytest.approx(sorted(near + far), abs=1e-9), (got, near, far)


def test_refusal_names_the_tensor_beyond_the_triangle_limit_that_would_fit():
    """Kills ``abs(T(x) - target) -> abs(T(x) + target)`` in the check of
    ``_triangle_hint`` (the hint was never printed, and no test read it):
    the thick plate of tests/conftest has Izz = Ixx + Iyy, the triangle
    limit, so a torsion period of Izz = 280 kg m^2 (forward model: the
    tensor diag(Ixx, Iyy, 280), positive definite, breaking the triangle
    inequality) is out of the admissible range, and the refusal names that
    Izz, to its 6 printed digits, and the other moments it breaks the
    inequality with (kills ``ij[0] == ij[1] -> ij[1] == ij[1]``, which
    listed the products too)."""
    from bifilar.errors import InputError

    s = trapezoid(h=0.5)
    I = s.inertia.copy()
    assert I[2, 2] == pytest.approx(I[0, 0] + I[1, 1], rel=1e-12)  # on the limit
    I[2, 2] = 280.0
    T = linear_modes(replace(s, inertia=I), rest_pose(s)).get("torsion").period
    ms = MeasurementSet([Hanging("h", s, np.eye(3))], [Measurement("torsion", float(T), 1e-4, "period", "--period")])
    with pytest.raises(InputError) as ei:
        invert(ms, solve_for=["Izz"], ladder=False, method="linear")
    msg = ei.value.message
    assert "Izz = 280 kg m^2 would reproduce it but breaks the triangle inequality" in msg, msg
    # "with the other components as given (...)": the other moments, not the products
    assert f"(Ixx = {I[0, 0]:.6g}, Iyy = {I[1, 1]:.6g})" in msg, msg


def test_slip_hint_counts_cycles_up_to_100_and_aliases_up_to_10():
    """Kills ``range(2, SLIP_MAX_CYCLES + 1) -> - 1`` and ``range(2,
    SLIP_MAX_ALIAS + 1) -> + 2``: the documented bounds are a total of up
    to 100 cycles and an alias of up to 1/10 (roots.slip_hint), both ends
    included.  A reachable range 1.000 +- 0.3 % holds 100 x 1 s / 100 only
    (1 s x 100 / 99 is 1 % long), and 1 s / 10 x 10 only."""
    from bifilar.estimation.roots import slip_hint

    rng = [(0.997, 1.003)]
    assert "it is 100 times a reachable period" in slip_hint(100.0, rng)
    assert slip_hint(101.0, rng) == ""
    assert "1/N of a reachable period for N = 10 " in slip_hint(0.1, rng)
    assert slip_hint(1 / 11, rng) == ""

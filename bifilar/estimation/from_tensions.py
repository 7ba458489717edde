"""Moments of inertia from a motion and its wire tensions (thesis 7.2.2).

Euler's equations in body axes, I alpha + w x (I w) = sum_i p_i x f_i (f_i
the wire forces in body axes), are linear in the six tensor components.
Stacking every time sample gives an overdetermined linear system solved by
least squares, with a sandwich covariance from the residuals (robust to
torque rows of different noise and to serially correlated load-cell noise,
:func:`_score_covariance`, corrected for the residuals' leverage by
:func:`_leverage_correction`) and Student-t intervals with the std's
effective degrees of freedom (tests/test_coverage_tensions.py; coverage
on 100-2000-sample records in docs/design.md).  The design
matrix's conditioning says which axes the motion excites: a component whose
relative standard uncertainty is large (or whose column is nearly dependent)
is reported as poorly excited -- the thesis found the non-dominant axes
inaccurate for exactly this reason.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import math

import numpy as np

from ..analysis.tensions import wire_units
from ..scene import Scene

COMPONENTS = ("Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz")


@dataclass(frozen=True)
class TensionInertia:
    """Least-squares inertia estimate (kg m^2) from tensions.

    values, std : dict component -> value / standard uncertainty.
    correlation : (m, m) correlation matrix of the solved components.
    poorly_excited : components whose relative std exceeds ``threshold``.
    residual_rms : N m.  condition : condition number of the scaled design matrix.
    lag_window : samples of residual serial correlation the std accounts for
    (0: uncorrelated); see :func:`_score_covariance`.
    dof : dict component -> effective degrees of freedom of its std
    (Satterthwaite: ``3 (sum h_k^2)^2 / ((2 W + 3) sum h_k^4)``, ``h_k``
    sample k's contribution to the component's error, ``W`` the lag
    window; 3 = the fourth moment of a Gaussian; ``2 W + 3``, one lag
    more each side than the window sums: the window is chosen from the
    same data, and its spread adds variance that the fixed-window count
    ``2 W + 1`` ignores -- with it the dof was 1.2-1.5x the measured
    ``2 E[v]^2 / var(v)`` on 201-481-sample records, with ``2 W + 3``
    0.84-1.17 (white noise; conservative for correlated residuals), see
    tests/test_mutation_gaps.py; with the leverage-corrected variance,
    whose factor grows with the chosen window, 1.05-1.2 on 241 samples,
    the interval covering 95 %), used by :meth:`interval95`.
    """

    components: tuple
    values: dict
    std: dict
    correlation: np.ndarray
    poorly_excited: list
    residual_rms: float
    condition: float
    n_samples: int
    lag_window: int = 0
    dof: dict = field(default_factory=dict)

    def interval95(self, c: str, std: float | None = None) -> list:
        """[lo, hi] kg m^2: ``value +- t std``, Student's t with the std's
        effective degrees of freedom ``dof[c]`` (the std is itself
        estimated from the residuals; a serially correlated residual leaves
        few independent stretches to estimate it from).  ``std`` (kg m^2):
        a caller's larger std (the residual one with systematic terms added
        in quadrature) in place of ``self.std[c]``, with the same t."""
        from scipy import stats

        s = self.std[c] if std is None else float(std)
        nu = self.dof.get(c, np.inf)
        k = float(stats.t.ppf(0.975, nu)) if np.isfinite(nu) and nu > 0 else 1.959963984540054
        return [self.values[c] - k * s, self.values[c] + k * s]


def euler_design(omega: np.ndarray, alpha: np.ndarray, components=COMPONENTS) -> np.ndarray:
    """Design matrix (k, 3, m): (I alpha + w x I w) = A @ [components].

    omega, alpha : (k, 3) body-axes angular velocity (rad/s) and acceleration (rad/s^2).
    """
    k = omega.shape[0]
    cols = []
    for c in components:
        E = np.zeros((3, 3))
        i, j = {"Ixx": (0, 0), "Iyy": (1, 1), "Izz": (2, 2), "Ixy": (0, 1), "Ixz": (0, 2), "Iyz": (1, 2)}[c]
        E[i, j] = E[j, i] = 1.0
        Ew = omega @ E.T
        cols.append(alpha @ E.T + np.cross(omega, Ew))
    return np.stack(cols, axis=-1).reshape(k, 3, len(components))


def wire_torque_body(scene: Scene, com: np.ndarray, R: np.ndarray, tensions: np.ndarray) -> np.ndarray:
    """Torque of the wire forces about the CoM, body axes (k, 3), N m.

    tensions : (k, n) N (measured by load cells or from a model).
    """
    u = wire_units(scene, com, R)  # world, attachment -> anchor
    f_world = tensions[..., None] * u
    f_body = np.einsum("kji,knj->kni", R, f_world)  # R^T f
    return np.cross(scene.attachments[None, :, :], f_body).sum(axis=1)


def inertia_from_tensions(scene: Scene, t: np.ndarray, com: np.ndarray, R: np.ndarray, omega: np.ndarray,
                          tensions: np.ndarray, alpha: np.ndarray | None = None,
                          components=("Ixx", "Iyy", "Izz"), threshold: float = 0.01,
                          fix_poorly_excited: bool = True) -> TensionInertia:
    """Estimate inertia components by least squares over all samples of Euler's equations.

    With ``fix_poorly_excited`` (default) the components the motion does not
    excite are fixed at the scene's values and the others re-estimated: an
    unexcited column otherwise soaks up noise and drags the well-determined
    components with it.  The fixed ones are listed in ``poorly_excited`` and
    reported with their first-pass value and no std (NaN): the motion does
    not determine them, and the first pass's residual std does not bound
    their error (the Solar Boat's torsion gave Iyy 236 +- 3 kg m^2 for
    317, its residuals at rounding level).
    """
    first = _solve(scene, t, com, R, omega, tensions, alpha, tuple(components), threshold)
    if not fix_poorly_excited or not first.poorly_excited or len(first.poorly_excited) == len(first.components):
        return first
    components = tuple(components)
    keep = tuple(c for c in components if c not in first.poorly_excited)
    second = _solve(scene, t, com, R, omega, tensions, alpha, keep, threshold)
    values = {**first.values, **second.values}
    std = {**{c: math.nan for c in first.poorly_excited}, **second.std}
    idx = [components.index(c) for c in keep]
    corr = np.full((len(components), len(components)), np.nan)
    corr[np.ix_(idx, idx)] = second.correlation
    return TensionInertia(tuple(components), values, std, corr, list(first.poorly_excited),
                          second.residual_rms, second.condition, second.n_samples, second.lag_window,
                          {**first.dof, **second.dof})


def _solve(scene: Scene, t, com, R, omega, tensions, alpha, components, threshold) -> TensionInertia:
    """Estimate inertia components by least squares over all samples of Euler's equations.

    Parameters
    ----------
    t : (k,) s.  com : (k, 3) m, world.  R : (k, 3, 3) body -> world.
    omega : (k, 3) body-axes angular velocity, rad/s.  tensions : (k, n) N.
    alpha : (k, 3) body-axes angular acceleration, rad/s^2; if None it is
        differentiated from ``omega`` (second-order finite differences).
    components : the unknowns (principal moments by default; all six for the
        full tensor).  Components not solved for are taken from ``scene``.
    threshold : relative std above which a component is flagged poorly excited.
    """
    if alpha is None:
        alpha = np.gradient(omega, t, axis=0, edge_order=2)
    comps = tuple(components)
    x, A2, b2, scale = _least_squares(scene, com, R, omega, tensions, alpha, comps)
    r = A2 @ x - b2
    s2 = float(r @ r) / max(len(b2) - len(comps), 1)
    As = A2 / scale
    AtA = As.T @ As
    cond = float(np.linalg.cond(AtA)) ** 0.5
    bread = np.linalg.pinv(AtA)
    As3, r3 = As.reshape(len(t), 3, -1), r.reshape(len(t), 3)
    g = np.einsum("kim,ki->km", As3, r3)  # scores, (k, m)
    meat, lags = _score_covariance(g, len(comps))
    f = np.sqrt(_leverage_correction(As3, r3, bread, lags))
    cov = f[:, None] * (bread @ meat @ bread) * f[None, :] / np.outer(scale, scale)
    h2 = (g @ bread) ** 2  # each sample's share of each component's error, squared
    dof = 3 * h2.sum(axis=0) ** 2 / ((2 * lags + 3) * np.maximum((h2 ** 2).sum(axis=0), 1e-300))
    std = np.sqrt(np.maximum(np.diag(cov), 0))
    corr = cov / np.maximum(np.outer(std, std), 1e-300)
    values = dict(zip(comps, map(float, x)))
    stds = dict(zip(comps, map(float, std)))
    # a column at the rounding level of the torques (no motion about that
    # axis) fits rounding noise with a tiny residual: flag it by its size
    excited = _excited(scene, com, R, tensions, A2, len(t))
    poor = [c for j, c in enumerate(comps) if not excited[j] or not np.isfinite(stds[c]) or stds[c] <= 0
            or stds[c] > threshold * max(abs(values[c]), 1e-300)]
    return TensionInertia(comps, values, stds, corr, poor, float(np.sqrt(s2)), cond, int(len(t)), lags,
                          dict(zip(comps, map(float, dof))))


def _least_squares(scene: Scene, com, R, omega, tensions, alpha, comps: tuple):
    """(estimate (m,) kg m^2, design (3k, m), torques (3k,) N m, column
    scales) of Euler's equations over every sample, the components not in
    ``comps`` at the scene's values."""
    fixed = [c for c in COMPONENTS if c not in comps]
    A = euler_design(omega, alpha, comps)
    b = wire_torque_body(scene, com, R, tensions)
    if fixed:
        Af = euler_design(omega, alpha, fixed)
        idx = {"Ixx": (0, 0), "Iyy": (1, 1), "Izz": (2, 2), "Ixy": (0, 1), "Ixz": (0, 2), "Iyz": (1, 2)}
        xf = np.array([scene.inertia[idx[c]] for c in fixed])
        b = b - Af @ xf
    A2 = A.reshape(-1, len(comps))
    b2 = b.reshape(-1)
    scale = np.linalg.norm(A2, axis=0)
    scale[scale == 0] = 1.0
    x, *_ = np.linalg.lstsq(A2 / scale, b2, rcond=None)
    return x / scale, A2, b2, scale


def geometry_std(scene: Scene, est: TensionInertia, com, R, omega, tensions, alpha,
                 unc: dict | None = None) -> dict:
    """Standard uncertainty (kg m^2) of each determined component of ``est``
    from the config's geometry: the torque arms and wire directions come
    from the anchors and attachment points and the CoM (relative to the
    attachments) as written down, each off by its standard uncertainty
    (:func:`~bifilar.estimation.uncertainty.default_uncertainty`:
    ``position`` 1 mm per coordinate, ``com`` 2 mm; ``unc`` overrides).
    Each input moved by its std, the estimate re-solved (the same
    components, those fixed in ``est`` held); the
    contributions are added in quadrature (linear, independent inputs).

    The residuals cannot show this error: a recorded motion fits a rig 1 mm
    off nearly as well, the torque arms scaled.  Without it the std of a
    record's ``Izz`` was up to 7 times too small (z-scores' sd 2.2-6.8 with
    load-cell noise 0.5-0.05 % of the tension; docs/invert.md, "Audit,
    session 6").  SI units; body frame for the attachments, world for the
    anchors, as the config."""
    from .sensitivity import input_sigma, measured_inputs, perturb
    from .uncertainty import default_uncertainty

    unc = default_uncertainty(unc or {})
    # the components solved in est's final fit (all of them when none is excited: then none was fixed)
    comps = tuple(c for c in est.components if math.isfinite(est.std[c]))
    if not comps:
        return {}
    x0 = _least_squares(scene, com, R, omega, tensions, alpha, comps)[0]
    var = np.zeros(len(comps))
    for name in measured_inputs(scene):
        if not (name.startswith(("anchor.", "attachment.", "com."))):
            continue
        sx = input_sigma(scene, name, unc)
        if not sx > 0:
            continue
        x = _least_squares(perturb(scene, name, sx), com, R, omega, tensions, alpha, comps)[0]
        var += (x - x0) ** 2
    return dict(zip(comps, map(float, np.sqrt(var))))


def record_std(scene: Scene, est: TensionInertia, other: TensionInertia, com, R, omega, tensions, alpha,
               unc: dict | None = None) -> tuple[dict, dict, dict, dict]:
    """The uncertainty (kg m^2) of each component of ``est`` from a recorded
    motion: the residuals' std (``est.std``, Student's t with ``est.dof``),
    the difference from ``other`` (the same fit with the rates
    differentiated another way) and the config's geometry
    (:func:`geometry_std`), the last two systematic over the record, which
    the residuals cannot show (normal, known std).

    Returns (std: the three in quadrature; the geometry's part; the 95 %
    interval ``value +- sqrt((t s_res)^2 + (1.96 s_diff)^2 + (1.96
    s_geo)^2)``, each term expanded by its own factor as ``invert``'s
    interval (docs/invert.md, "The 95 % interval"); the equivalent degrees
    of freedom of that interval, ``t_{0.975, dof} = half-width / std``,
    inf for the normal 1.96).  NaN / None for a component the fit held
    fixed.  A Student factor of the residuals' few dof applied to the whole
    std made a record's interval 40 times its std where the geometry's
    known std dominates."""
    from scipy import stats

    from .uncertainty import Z95, equivalent_dof

    g = geometry_std(scene, est, com, R, omega, tensions, alpha, unc)
    std, interval, dof = {}, {}, {}
    for c in est.components:
        s_res, s_diff, s_geo = est.std[c], est.values[c] - other.values[c], g.get(c, 0.0)
        std[c] = float(math.hypot(math.hypot(s_res, s_diff), s_geo))
        nu = est.dof.get(c, math.inf)
        t = float(stats.t.ppf(0.975, nu)) if math.isfinite(nu) and nu > 0 else Z95
        half = math.sqrt((t * s_res) ** 2 + (Z95 * s_diff) ** 2 + (Z95 * s_geo) ** 2)
        interval[c] = [est.values[c] - half, est.values[c] + half]
        dof[c] = equivalent_dof(half / std[c]) if std[c] > 0 else math.nan
    return std, g, interval, dof


def _score_covariance(g: np.ndarray, m: int) -> tuple[np.ndarray, int]:
    """Covariance of the least-squares score ``sum_k A_k^T r_k`` (the
    sandwich's meat), robust to what the white-noise ``s^2 A^T A`` assumes
    away: the three torque rows of a sample share the same tension noise and
    differ in size (a bifilar's z torque is tens of times quieter than its
    x and y torques, so a pooled ``s^2`` overstated Izz's std ~20x), and a
    load cell's low-pass makes the residuals serially correlated (which
    made the white std too small).

    ``g`` (k, m): the scores ``g_k = A_k^T r_k`` (scaled design ``A_k``
    (3, m) of sample k, residuals ``r_k`` (3,), N m); the meat is
    ``sum_{|l| <= W} Gamma(l)`` with ``Gamma(l) = sum_k g_k g_{k+l}^T``,
    the lag window ``W`` chosen as the smallest with ``W >= 5 tau(W)``
    (Sokal's self-consistent window; ``tau`` the largest integrated
    autocorrelation time of the scores' components) and capped at k / 4,
    negative eigenvalues of the truncated sum clipped to zero.  Residuals
    stand in for the errors, so the sum is biased low (for the fitted
    parameters, ``m`` of them): :func:`_leverage_correction` removes that.
    Returns ``(meat, W)``.
    """
    k = g.shape[0]
    g0 = g.T @ g
    d0 = np.maximum(np.diag(g0), 1e-300)
    meat, tau, W = g0.copy(), np.ones(m), 0
    for lag in range(1, max(k // 4, 1) + 1):
        if lag >= 5 * tau.max():
            break
        G = g[lag:].T @ g[:-lag]
        meat += G + G.T
        tau += 2 * np.diag(G) / d0
        W = lag
    w, V = np.linalg.eigh(meat)
    meat = (V * np.maximum(w, 0)) @ V.T
    return meat, W


def _leverage_correction(As3: np.ndarray, r3: np.ndarray, bread: np.ndarray, W: int) -> np.ndarray:
    """(m,) factors by which the lag-window variance of each component is
    too small because it is built from residuals, not errors: the factor
    is ``Omega_jj / E[V_jj]`` under a working model of the errors, so
    multiplying by it makes the variance unbiased under that model.

    ``V = sum_{|k - l| <= W} h_k h_l^T`` with ``h_k = P_k r_k``,
    ``P_k = bread As_k^T`` ((m, 3), sample k's influence on the estimate;
    ``As3`` (k, 3, m) the scaled design, ``r3`` (k, 3) residuals,
    ``bread = (As^T As)^-1``).  Working model: stationary errors whose
    3x3 covariance between samples ``d`` apart is the residuals' own,
    ``C(d) = sum_k r_{k+d} r_k^T / k``, for ``|d| <= W`` and zero beyond
    (the window ``V`` itself assumes; the three torque rows of a sample
    share its tension noise and differ in size; the scale cancels).  Then
    ``r = (I - H) e`` with ``H_kl = As_k P_l``; with ``D_k = P_k As_k``,
    ``Y_l = sum_d P_{l+d} C(d)``, ``Z_l = Y_l P_l^T`` and the model's
    covariance of the estimate ``Omega = sum_l Z_l``:

        E[V] = Omega - sum_{|k - l| <= W} (D_k Z_l + (D_k Z_l)^T - D_k Omega D_l^T).

    The expansion behind HC2's ``r_k^2 / (1 - h_kk)`` (unbiased for
    homoskedastic errors), carried over the window's cross products: the
    scores sum to zero (the normal equations), so each lag's sum is low
    by about the variance of the estimate -- with white errors
    ``(2 W + 1) Omega / k`` in all (``W = 0``, one row a sample, equal
    leverages: ``k / (k - m)``).  The serial correlation is in the model
    because it changes the size of that loss: scores modulated by the
    motion's oscillation lose less over a long window than white ones,
    and the white model's factor overstated an AR(1) 0.8 std by 10 % on
    200 samples.  Coverage it buys on 100-2000-sample records: docs/design.md.
    A factor of 1 where the model has no positive variance to correct
    (residuals all zero: an exact fit).
    """
    k, _, m = As3.shape
    P = np.einsum("mn,kin->kmi", bread, As3)  # (k, m, 3)
    P2 = P.reshape(k * m, 3)  # rows (sample, component): one matrix product a lag
    Y2 = P2 @ (r3.T @ r3 / k)
    for d in range(1, W + 1):
        C = r3[d:].T @ r3[:-d] / k  # C(d): r_{l+d} r_l^T
        Y2[:-d * m] += P2[d * m:] @ C
        Y2[d * m:] += P2[:-d * m] @ C.T
    Y = Y2.reshape(k, m, 3)
    omega = np.einsum("kmi,kni->mn", Y, P)
    omega = (omega + omega.T) / 2
    expected = np.diag(omega).copy()
    for j in range(m):
        Dj = np.einsum("ki,kin->kn", P[:, j, :], As3)  # row j of D_k, (k, m)
        Zj = np.einsum("kia,ka->ki", Y, P[:, j, :])  # column j of Z_k, (k, m)
        expected[j] -= 2 * np.sum(Dj * _window_sum(Zj, W))
        expected[j] += np.sum((Dj @ omega) * _window_sum(Dj, W))
    ok = (np.diag(omega) > 0) & (expected > 0)
    return np.where(ok, np.diag(omega) / np.where(ok, expected, 1.0), 1.0)


def _window_sum(x: np.ndarray, W: int) -> np.ndarray:
    """(k, ...) ``sum_{|l - k| <= W} x_l`` (the record's ends truncate the window)."""
    c = np.concatenate([np.zeros((1,) + x.shape[1:]), np.cumsum(x, axis=0)])
    i = np.arange(len(x))
    return c[np.minimum(i + W + 1, len(x))] - c[np.maximum(i - W, 0)]


EXCITATION_FLOOR = 1e-8
"""A component is excited when the torque its column explains about some
body axis (at the scale of the largest principal moment) exceeds this
fraction of the gross torque of the wires about that axis (the sum of the
magnitudes of each wire's torque component).  Rounding is relative to
what is summed: the net torque of a body at rest is ~1e-16 of the gross
one about each axis; differentiating rounding-level angular velocities for
the acceleration amplifies that by 1 / (omega dt) ~ 1e2-1e3.  1e-8 keeps
four orders of margin above that, while a motion of 1e-8 rad still counts.

The relative-std check cannot replace it: rounding is not random noise,
and a symmetric torsion's unmoving roll axis fits its rounding-level
torques with a relative std of 0.2 % (Ixx 202.7 for 208.3 kg m^2,
tests/test_mutation_gaps.py).  Per axis, not against the gross torque of
all three axes: a tiny torsion (1e-9 rad) has z torques at 1e-9 of the
wires' x torques but computed to rounding of their own size, and
determines Izz to ~1e-16."""


def _excited(scene: Scene, com, R, tensions, A2: np.ndarray, k: int) -> np.ndarray:
    """(m,) bool: whether each design column of ``A2`` ((3k, m), 1/s^2)
    carries, about some body axis, a torque above :data:`EXCITATION_FLOOR`
    of the gross wire torque about that axis (N m, RMS over the k samples)."""
    u = wire_units(scene, com, R)  # world, attachment -> anchor
    f_body = np.einsum("kji,knj->kni", R, tensions[..., None] * u)
    gross = np.abs(np.cross(scene.attachments[None, :, :], f_body)).sum(axis=1)  # (k, 3) N m
    floor = EXCITATION_FLOOR * np.sqrt(np.mean(gross ** 2, axis=0))  # (3,)
    I_scale = float(np.max(np.linalg.eigvalsh(scene.inertia)))  # kg m^2
    A = A2.reshape(k, 3, -1)
    explained = I_scale * np.sqrt(np.mean(A ** 2, axis=0))  # (3, m) RMS over samples, N m
    return np.any(explained > floor[:, None], axis=0)

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

from dataclasses import dataclass, field, replace

import math

import numpy as np

from ..analysis.tensions import wire_units
from .design_noise import design_noise
from ..scene import Scene

COMPONENTS = ("Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz")
_INDEX = {"Ixx": (0, 0), "Iyy": (1, 1), "Izz": (2, 2), "Ixy": (0, 1), "Ixz": (0, 2), "Iyz": (1, 2)}


@dataclass(frozen=True)
class TensionInertia:
    """Least-squares inertia estimate (kg m^2) from tensions.

    values, std : dict component -> value / standard uncertainty.
    correlation : (m, m) correlation matrix of the solved components.
    poorly_excited : components the motion does not determine (torques at
    rounding level, or a std above ``threshold`` of the component's scale,
    :func:`component_scale`): exactly those whose ``std`` is NaN (a single
    pass of ``_solve``: worst first).
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
    std_geometry : dict component -> kg m^2, the config geometry's part of
    the uncertainty (:func:`geometry_jacobian`), kept apart from ``std``
    (the residuals', with the geometry's share of the residuals removed,
    see :func:`_solve`); None when the fit was told the geometry
    is exact (``geometry=None``: a simulated motion).
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
    std_geometry: dict | None = None

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


POORLY_EXCITED = 1 / 1.959963984540054
"""A component whose standard uncertainty exceeds this fraction of its
scale (:func:`component_scale`) is poorly excited and gets no value: its
95 % interval would be wider than +-1 scale, so the record cannot tell even
its size (session 20; before, 1 % of the value, which flagged every product
of inertia near zero and disagreed with the components the CLI printed)."""


def component_scale(scene: Scene, c: str) -> float:
    """kg m^2: the scale a component's std is judged against
    (:data:`POORLY_EXCITED`): ``I_ii`` for a moment, ``sqrt(I_ii I_jj)``
    for a product ``I_ij`` (the bound ``|I_ij| <= sqrt(I_ii I_jj)`` of a
    positive definite tensor; a product is often zero, so its own value is
    no scale), from the config's (``scene``'s) moments."""
    i, j = {"Ixx": (0, 0), "Iyy": (1, 1), "Izz": (2, 2), "Ixy": (0, 1), "Ixz": (0, 2), "Iyz": (1, 2)}[c]
    return float(math.sqrt(abs(scene.inertia[i, i] * scene.inertia[j, j])))


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
                          components=("Ixx", "Iyy", "Izz"), threshold: float = POORLY_EXCITED,
                          fix_poorly_excited: bool = True, geometry: dict | None = None,
                          alpha_noise: np.ndarray | None = None, alpha_noise_rse: float = 0.0,
                          hold: tuple = (), min_lag: int = 0) -> TensionInertia:
    """Estimate inertia components by least squares over all samples of Euler's equations.

    With ``fix_poorly_excited`` (default) the components the motion does not
    excite (torques at rounding level, or a std above ``threshold`` of the
    component's scale, :func:`component_scale`) are fixed at the scene's
    values and the others re-estimated: an unexcited column otherwise soaks
    up noise and drags the well-determined components with it.  The fixed
    ones are listed in ``poorly_excited`` and reported with their first-pass
    value and no std (NaN), also where every requested component is poorly
    excited (none is then fitted): the motion does not determine them, and
    the first pass's residual std does not bound their error (the Solar
    Boat's torsion gave Iyy 236 +- 3 kg m^2 for 317, its residuals at
    rounding level).

    ``geometry``: the standard uncertainties of the config's geometry when
    it is measured (a dict of overrides of
    :func:`~bifilar.estimation.uncertainty.default_uncertainty`, ``{}`` for
    the defaults: ``position`` m, ``com`` m): its part of each component's
    uncertainty is returned as ``std_geometry``, and its share of the
    residuals is removed before their std is taken (see :func:`_solve`);
    the rule for ``poorly_excited`` then applies to both in quadrature.  None (default): the geometry is exact.

    ``alpha_noise`` (3, 3) (rad/s^2)^2: the covariance of the noise each
    sample of ``alpha`` (body axes) carries when it is differentiated from
    noisy poses (:func:`~bifilar.estimation.motion_record.read_motion`), and
    ``alpha_noise_rse`` the relative standard error of that estimate: the
    least squares are then corrected for the noise in their design
    (:mod:`~bifilar.estimation.design_noise`), which otherwise pulls every
    estimate toward zero.  None (default): the rates are exact.

    ``hold``: components held at the scene's values from the start and
    listed as poorly excited (a caller's reason: the products of a record
    with attitude noise, :func:`~bifilar.estimation.motion_record.record_inertia`).

    ``min_lag``: the least lag window (samples) of the sandwich's scores
    (:func:`_score_covariance`): a record's rates differentiated by a
    filter of ``w`` samples carry noise correlated over ``w - 1`` samples.
    """
    if alpha is None:
        alpha = np.gradient(omega, t, axis=0, edge_order=2)
    B = None  # the torques' change per std of each geometric input, (3k, p) N m, at the motion-fitted tensions
    if geometry is not None:
        B = geometry_jacobian(scene, com, R, _motion_fit(com, R, omega, alpha, tensions), geometry)[1]
        B = B.reshape(3 * len(t), -1)
    noise = None if alpha_noise is None else design_noise(alpha_noise)
    components = tuple(components)
    if hold:  # held from the start (at the config's values), as poorly excited ones
        return _held(scene, components, lambda cs: _solve(scene, t, com, R, omega, tensions, alpha, cs, threshold, B,
                                                          noise, alpha_noise_rse, min_lag),
                     [c for c in components if c in hold])
    first = _solve(scene, t, com, R, omega, tensions, alpha, components, threshold, B, noise, alpha_noise_rse, min_lag)
    if not fix_poorly_excited or not first.poorly_excited:
        return first
    return _held(scene, components, lambda cs: _solve(scene, t, com, R, omega, tensions, alpha, cs, threshold, B, noise,
                                                      alpha_noise_rse, min_lag), [], first)


def _held(scene: Scene, components: tuple, solve, poor: list, first: TensionInertia | None = None) -> TensionInertia:
    """The fit of :func:`inertia_from_tensions` with its poorly excited
    components held at the scene's values: ``poor`` (held from the start)
    and, one pass at a time, the worst that a pass of ``solve`` (a function
    of the components to fit) flags; ``first`` the pass on every component
    when there was one (its values kept for the held components, whose std
    is NaN); else the held ones carry the scene's values."""
    if first is not None:
        poor = [first.poorly_excited[0]]
    # a poorly excited component gets no value (session 20: the list and the nulls agree); the worst one
    # (_solve lists them worst first) is held at the config's value and the others re-fitted, until no fitted
    # one is poorly excited: one unexcited column can make every std of a pass NaN or huge (the drone's torsion
    # solving Izz, Ixz, Iyz and Ixx), so they are held one at a time (at most m passes)
    fit = None
    while True:
        keep = tuple(c for c in components if c not in poor)
        if not keep:
            break
        fit = solve(keep)
        if not fit.poorly_excited:
            break
        poor.append(fit.poorly_excited[0])
    keep = tuple(c for c in components if c not in poor)
    fitted = fit if keep else None
    ref = fitted or first or solve(components)  # the last for the fit's figures only: every component held
    values = {c: float(scene.inertia[_INDEX[c]]) for c in components}
    values.update(first.values if first is not None else {})
    values.update(fitted.values if fitted else {})
    nan = {c: math.nan for c in poor}
    idx = [components.index(c) for c in keep]
    corr = np.full((len(components), len(components)), np.nan)
    if fitted:
        corr[np.ix_(idx, idx)] = fitted.correlation
    geo = None if ref.std_geometry is None else {**nan, **(fitted.std_geometry if fitted else {})}
    return TensionInertia(components, values, {**nan, **(fitted.std if fitted else {})}, corr,
                          [c for c in components if c in poor], ref.residual_rms, ref.condition, ref.n_samples,
                          ref.lag_window, {**(first.dof if first else {}), **(fitted.dof if fitted else {})}, geo)


def _solve(scene: Scene, t, com, R, omega, tensions, alpha, components, threshold,
           B: np.ndarray | None = None, noise: np.ndarray | None = None, noise_rse: float = 0.0,
           min_lag: int = 0) -> TensionInertia:
    """Estimate inertia components by least squares over all samples of Euler's equations.

    Parameters
    ----------
    t : (k,) s.  com : (k, 3) m, world.  R : (k, 3, 3) body -> world.
    omega : (k, 3) body-axes angular velocity, rad/s.  tensions : (k, n) N.
    alpha : (k, 3) body-axes angular acceleration, rad/s^2.
    components : the unknowns (principal moments by default; all six for the
        full tensor).  Components not solved for are taken from ``scene``.
    threshold : the std, as a fraction of the component's scale
        (:func:`component_scale`), above which it is flagged poorly excited.
    B : (3k, p) N m, the torques' change per standard uncertainty of each
        geometric input (:func:`geometry_jacobian`, at the tensions of
        :func:`_motion_fit`), None when the geometry is exact.
    noise, noise_rse : the design's per-sample error covariance (6, 6) and
        the relative standard error of that estimate
        (:mod:`~bifilar.estimation.design_noise`), or None: exact rates.
    min_lag : the least lag window of the sandwich (:func:`_score_covariance`).

    The config's geometry enters the torques ``b`` only (the design ``A``
    is the motion's), linearly over its uncertainty: ``b = A theta + B
    delta + e`` with ``B`` the torques' derivative per standard uncertainty
    of each input (:func:`geometry_jacobian`), ``delta`` the inputs' errors
    in stds (independent, unit variance) and ``e`` the load-cell noise.  The
    estimate moves by ``G delta``, ``G = (A^T A)^-1 A^T B``: that is the
    geometry's std, ``sqrt(sum_j G_ij^2)``.  The residuals are ``(I - H)(B
    delta + e)``: a config off by its std leaves torque residuals of its
    own, systematic over the record, that the residuals' (sandwich) std
    counted as noise -- the geometry's error counted a second time,
    through the residuals' ``(I - H) B delta``: 5-700 times the noise's std,
    z sd 0.5-0.75, 99-100 % coverage (docs/invert.md, "Audit, session 7:
    tensions").  So the geometry's share of the residuals along each
    direction of ``(I - H) B`` is removed before the sandwich
    (:func:`_geometry_shrinkage`), and :func:`_leverage_correction` is told
    of the directions and their weights (the noise removed with them).
    """
    comps = tuple(components)
    x, A2, b2, scale, eiv = _least_squares(scene, com, R, omega, tensions, alpha, comps, noise)
    r = A2 @ x - b2
    s2 = float(r @ r) / max(len(b2) - len(comps), 1)
    As = A2 / scale
    AtA = As.T @ As if eiv is None else As.T @ As - len(t) * eiv[0]
    cond = float(np.linalg.cond(AtA)) ** 0.5
    bread = np.linalg.pinv(AtA)
    geo, extra, weight = None, None, None
    if B is not None:
        geo = np.sqrt(np.sum(((bread @ (As.T @ B)) / scale[:, None]) ** 2, axis=1))
        extra, weight = _geometry_shrinkage(As, B, r)
        extra, weight = extra[:, weight > 1e-9], weight[weight > 1e-9]  # the others change nothing
        r = r - extra @ (weight * (extra.T @ r))
    As3, r3 = As.reshape(len(t), 3, -1), r.reshape(len(t), 3)
    g = _scores(As3, r3)  # (k, m)
    if eiv is not None:  # the corrected normal equations' scores, less each sample's expected noise product (r = A x - b)
        g = g - eiv[1]
    meat, lags = _score_covariance(g, len(comps), min_lag)
    f = np.sqrt(_leverage_correction(As3, r3, bread, lags, extra, weight))
    cov = f[:, None] * (bread @ meat @ bread) * f[None, :] / np.outer(scale, scale)
    h2 = (g @ bread) ** 2  # each sample's share of each component's error, squared
    dof = 3 * h2.sum(axis=0) ** 2 / ((2 * lags + 3) * np.maximum((h2 ** 2).sum(axis=0), 1e-300))
    std = np.sqrt(np.maximum(np.diag(cov), 0))
    corr = cov / np.maximum(np.outer(std, std), 1e-300)
    if eiv is not None:  # the correction's own uncertainty (the pose noise is estimated), and where it fails
        from .design_noise import correction_std, undetermined_by_noise

        std = np.hypot(std, correction_std(x, eiv[2], noise_rse))
        std[undetermined_by_noise(len(t) * np.diag(eiv[0]), AtA)] = np.nan
    values = dict(zip(comps, map(float, x)))
    stds = dict(zip(comps, map(float, std)))
    total = std if geo is None else np.hypot(std, geo)
    # a column at the rounding level of the torques (no motion about that
    # axis) fits rounding noise with a tiny residual: flag it by its size
    excited = _excited(scene, com, R, tensions, A2, len(t))
    ratio = np.array([total[j] / max(component_scale(scene, c), 1e-300) for j, c in enumerate(comps)])
    bad = ~excited | ~np.isfinite(ratio) | (std <= 0)
    poor = [c for j, c in enumerate(comps) if bad[j] or ratio[j] > threshold]
    # worst first: a column at rounding level, then the one whose noise share is largest (a column swamped by
    # the poses' noise makes every corrected std of the pass NaN), then the largest std for its scale
    share = np.zeros(len(comps)) if eiv is None else np.diag(len(t) * eiv[0]) / np.maximum(np.diag(As.T @ As), 1e-300)
    poor = sorted(poor, key=lambda c: (bool(excited[comps.index(c)]), -share[comps.index(c)],
                                       -np.nan_to_num(ratio[comps.index(c)], nan=np.inf)))
    return TensionInertia(comps, values, stds, corr, poor, float(np.sqrt(s2)), cond, int(len(t)), lags,
                          dict(zip(comps, map(float, dof))), None if geo is None else dict(zip(comps, map(float, geo))))


def _motion_fit(com, R, omega, alpha, tensions: np.ndarray) -> np.ndarray:
    """(k, n) N: the measured tensions least-squares fitted, wire by wire,
    on the motion's own signals (a constant, the CoM (3), the rotation
    matrix (9), omega (3), alpha (3), the products omega_a omega_b (6)): the
    true tensions are such a function of the motion to first order in a
    small one (the centripetal terms second order); the noise keeps only
    its part in those 25 directions.  :func:`_solve` differentiates the
    torques w.r.t. the geometry at these tensions: at the measured ones
    the derivative carried the load-cell noise itself, and projecting its
    directions out of the residuals removed noise (the 1000 kg bifilar's
    residual std 2.6x too small with the shrinkage of
    :func:`_geometry_shrinkage`, 10x without); with the fitted ones z sd
    1.03, as without projection.  A model error of the fit moves the
    derivative by that error's share of the tension (a systematic term of
    second order in the motion times the geometry's error)."""
    k = len(com)
    w = omega
    X = np.column_stack([np.ones(k), com, R.reshape(k, 9), w, alpha, w[:, [0, 0, 0, 1, 1, 2]] * w[:, [0, 1, 2, 1, 2, 2]]])
    scale = np.linalg.norm(X, axis=0)
    scale[scale == 0] = 1.0
    c, *_ = np.linalg.lstsq(X / scale, tensions, rcond=None)
    return (X / scale) @ c


GEOMETRY_RANK_RTOL = 1e-6
"""Directions of the geometry's residuals ``(I - H) B`` (:func:`_solve`)
with a singular value below this fraction of the largest stay in the
residuals: the part of the geometry's error they carry is at most 1e-6 of
the largest one's, below the load-cell noise unless that is below ~1e-8
of the tension (their shrinkage weight would be ~0 anyway); and they are
found from the Gram matrix ``C^T C`` (50 times cheaper than an SVD of the
(3k, p) ``C``), whose eigenvalues are exact to ~1e-16 of the largest,
1e-4 of the smallest one kept."""


def _geometry_shrinkage(As: np.ndarray, B: np.ndarray, r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(Q (3k, q), lam (q,)): the directions of the residuals ``(I - H) B``
    that the geometry's errors leave and how much of ``r`` along each is
    theirs (``As`` (3k, m) the scaled design, ``B`` (3k, p) the torques per
    std of each input, :func:`geometry_jacobian`; ``r`` (3k,) the
    residuals, N m); :func:`_solve` removes ``Q (lam * Q^T r)``.

    ``(I - H) B = Q diag(s) V^T`` (SVD, the columns of ``Q`` orthogonal to
    the design's; ``s`` above :data:`GEOMETRY_RANK_RTOL`): the geometry's
    error ``delta`` (unit normal per input) leaves ``s_i (V^T delta)_i``
    along ``q_i``, variance ``s_i^2``; the noise leaves variance ``n_i =
    q_i^T S q_i`` (``S`` the residuals' serially correlated covariance
    with every ``q_i`` removed, :func:`_banded_times`).  The part of ``r``
    along ``q_i`` that is the geometry's, in expectation given ``r`` (normal
    prior and noise), is ``lam_i = s_i^2 / (s_i^2 + n_i)`` of it.  Not a
    plain projection (``lam = 1``): ``B`` is computed from the measured,
    noisy tensions, and a combination of inputs whose true torques cancel
    (the two anchors' x of a symmetric bifilar, ``T_1 - T_2``) is then
    the tension noise itself; projected out, it took the noise with it
    (the exact 1000 kg bifilar's residual std 10x too small).  Such a
    direction has ``s_i`` at the noise's level, ``lam_i ~ 1e-3``; a real
    one (1 mm is 1e2-1e4 load-cell sigmas of torque over a record) ~ 1."""
    if B.shape[1] == 0:
        return np.zeros((len(B), 0)), np.zeros(0)
    Qa = _design_basis(As)
    C = B - Qa @ (Qa.T @ B)
    C -= Qa @ (Qa.T @ C)  # twice: the columns of B along As are large, C the small difference
    w, V = np.linalg.eigh(C.T @ C)
    keep = w > GEOMETRY_RANK_RTOL ** 2 * max(float(w.max()), 0.0)
    if not keep.any():
        return np.zeros((len(B), 0)), np.zeros(0)
    s2 = w[keep]
    Q = C @ (V[:, keep] / np.sqrt(s2))
    Q = Q @ np.linalg.inv(np.linalg.cholesky(Q.T @ Q)).T  # orthonormal to rounding (Cholesky QR, second pass)
    k, m = len(r) // 3, As.shape[1]
    rh3 = (r - Q @ (Q.T @ r)).reshape(k, 3)
    W = _score_covariance(_scores(As.reshape(k, 3, m), rh3), m)[1]
    Q3 = Q.reshape(k, 3, -1)
    noise = np.sum(Q3 * _banded_times(Q3, rh3, W), axis=(0, 1))
    return Q, s2 / np.maximum(s2 + np.maximum(noise, 0), 1e-300)


def _scores(As3: np.ndarray, r3: np.ndarray) -> np.ndarray:
    """(k, m) least-squares scores ``As_k^T r_k`` (``As3`` (k, 3, m), ``r3`` (k, 3))."""
    return np.sum(As3 * r3[:, :, None], axis=1)


def _design_basis(As: np.ndarray) -> np.ndarray:
    """(3k, rank) orthonormal basis of the scaled design's columns, the
    rank as ``pinv(As^T As)`` counts it (singular values of ``As`` above
    ``sqrt(1e-15)`` of the largest)."""
    U, sv, _ = np.linalg.svd(As, full_matrices=False)
    return U[:, sv > math.sqrt(1e-15) * max(float(sv.max()), 1e-300)] if sv.size else U


def _least_squares(scene: Scene, com, R, omega, tensions, alpha, comps: tuple, noise: np.ndarray | None = None):
    """(estimate (m,) kg m^2, design (3k, m), torques (3k,) N m, column
    scales, errors-in-variables terms or None) of Euler's equations over
    every sample, the components not in ``comps`` at the scene's values.

    ``noise`` (6, 6): the per-sample covariance of the design's errors over
    :data:`COMPONENTS` (:func:`design_noise`, from the noise of an ``alpha``
    differentiated from noisy poses), or None.  Given, the normal equations
    are corrected for it (:func:`~bifilar.estimation.design_noise`):
    ``(A^T A - k S_cc) x = A^T b + k S_cf x_f`` (``c`` the solved, ``f``
    the held components), and the last item is ``(S_cc scaled (m, m),
    each sample's score offset (m,) scaled, the plain least-squares
    estimate (m,) kg m^2)``."""
    fixed = [c for c in COMPONENTS if c not in comps]
    A = euler_design(omega, alpha, comps)
    b = wire_torque_body(scene, com, R, tensions)
    xf = np.zeros(0)
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
    if noise is None:
        return x / scale, A2, b2, scale, None
    from .design_noise import corrected_normal_equations

    xc, S_cc, offset = corrected_normal_equations(A2 / scale, b2, scale, noise, comps, fixed, xf, len(omega))
    return xc / scale, A2, b2, scale, (S_cc, offset, x / scale)


GEOMETRY_INPUTS = ("anchor.", "attachment.", "com.")
"""The measured inputs (:func:`~bifilar.estimation.sensitivity.measured_inputs`)
the wire torques depend on: the torque arms and the wire directions."""


def geometry_jacobian(scene: Scene, com: np.ndarray, R: np.ndarray, tensions: np.ndarray,
                      unc: dict | None = None) -> tuple[list, np.ndarray]:
    """(names, J (k, 3, p)): the change of :func:`wire_torque_body` (N m,
    body axes) per standard uncertainty of each geometric input of the
    config (:data:`GEOMETRY_INPUTS`, in the order of
    :func:`~bifilar.estimation.sensitivity.measured_inputs`; the std from
    :func:`~bifilar.estimation.uncertainty.default_uncertainty` with ``unc``'s
    overrides, ``position`` 1 mm per coordinate, ``com`` 2 mm; inputs with a
    zero std are left out), analytic: with ``v = anchor - com - R a`` (world),
    ``u = v / |v|``, ``N = (I - u u^T) / |v|`` and the body force ``f = T
    R^T u``, the torque ``a x f`` moves by ``a x (T R^T N e)`` for an anchor
    moved along world axis ``e``, by ``e x f - a x (T R^T N R e)`` for an
    attachment moved along body axis ``e``, and a CoM moved by ``d`` moves
    every attachment by ``-d`` (:func:`~bifilar.estimation.sensitivity.perturb`).
    com (k, 3) m world; R (k, 3, 3) body -> world; tensions (k, n) N."""
    from .sensitivity import input_sigma, measured_inputs
    from .uncertainty import default_uncertainty

    unc = default_uncertainty(unc or {})
    names = [nm for nm in measured_inputs(scene) if nm.startswith(GEOMETRY_INPUTS) and input_sigma(scene, nm, unc) > 0]
    k = len(com)
    if not names:
        return [], np.zeros((k, 3, 0))
    a = scene.attachments
    v = scene.anchors[None] - com[:, None, :] - np.einsum("kij,nj->kni", R, a)  # (k, n, 3) world
    length = np.linalg.norm(v, axis=-1)[..., None, None]
    u = v / length[..., 0]
    N = (np.eye(3) - u[..., :, None] * u[..., None, :]) / length  # du/dv, (k, n, 3, 3)
    f = np.einsum("kji,knj->kni", R, tensions[..., None] * u)  # body force (k, n, 3)
    TRN = tensions[..., None, None] * (np.swapaxes(R, 1, 2)[:, None] @ N)  # df/dv (k, n, 3, 3)
    anchor = _skew(a) @ TRN  # world axes
    attachment = -_skew(f) - anchor @ R[:, None]  # body axes
    per = {"anchor": anchor, "attachment": attachment}
    cols = []
    for nm in names:
        part = nm.split(".")
        e = "xyz".index(part[-1])
        col = -attachment[:, :, :, e].sum(axis=1) if part[0] == "com" else per[part[0]][:, int(part[1]) - 1, :, e]
        cols.append(col * input_sigma(scene, nm, unc))
    return names, np.stack(cols, axis=-1)


def _skew(x: np.ndarray) -> np.ndarray:
    """(..., 3, 3) matrices ``[x]_x`` with ``[x]_x y = x cross y``."""
    z = np.zeros(x.shape[:-1])
    return np.stack([np.stack([z, -x[..., 2], x[..., 1]], -1),
                     np.stack([x[..., 2], z, -x[..., 0]], -1),
                     np.stack([-x[..., 1], x[..., 0], z], -1)], -2)


def record_std(est: TensionInertia, other: TensionInertia | None = None,
               differentiation: dict | None = None) -> tuple[dict, dict, dict, dict]:
    """The uncertainty (kg m^2) of each component of ``est`` from a recorded
    motion: the residuals' std (``est.std``, Student's t with ``est.dof``),
    the differentiation's: ``differentiation[c]`` (kg m^2) when given, else
    the difference from ``other`` (the same fit with the rates
    differentiated another way; NaN for a component it lacks), and the config's geometry
    (``est.std_geometry``: ``est`` must be fitted with ``geometry=``, which
    also keeps the geometry's residuals out of ``est.std``), the last two
    systematic over the record, which the residuals cannot show (normal,
    known std).

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

    if est.std_geometry is None:
        raise ValueError("record_std: est was fitted with the geometry exact (geometry=None); fit it with "
                         "geometry={} (or the stated uncertainties) so that its residual std leaves the geometry out")
    g = est.std_geometry
    std, interval, dof = {}, {}, {}
    for c in est.components:
        s_diff = differentiation[c] if differentiation is not None else est.values[c] - other.values.get(c, math.nan)
        s_res, s_geo = est.std[c], g.get(c, 0.0)
        std[c] = float(math.hypot(math.hypot(s_res, s_diff), s_geo))
        nu = est.dof.get(c, math.inf)
        t = float(stats.t.ppf(0.975, nu)) if math.isfinite(nu) and nu > 0 else Z95
        half = math.sqrt((t * s_res) ** 2 + (Z95 * s_diff) ** 2 + (Z95 * s_geo) ** 2)
        interval[c] = [est.values[c] - half, est.values[c] + half]
        dof[c] = equivalent_dof(half / std[c]) if std[c] > 0 else math.nan
    return std, dict(g), interval, dof


def _score_covariance(g: np.ndarray, m: int, min_lag: int = 0) -> tuple[np.ndarray, int]:
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
    autocorrelation time of the scores' components), at least ``min_lag``
    (the span of a differentiating filter's noise correlation, which the
    scores' estimated autocorrelation can miss) and capped at k / 4,
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
        if lag >= 5 * tau.max() and lag > min_lag:
            break
        G = g[lag:].T @ g[:-lag]
        meat += G + G.T
        tau += 2 * np.diag(G) / d0
        W = lag
    w, V = np.linalg.eigh(meat)
    meat = (V * np.maximum(w, 0)) @ V.T
    return meat, W


def _leverage_correction(As3: np.ndarray, r3: np.ndarray, bread: np.ndarray, W: int,
                         extra: np.ndarray | None = None, weight: np.ndarray | None = None) -> np.ndarray:
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
    share its tension noise and differ in size; the scale cancels): ``S``
    (3k, 3k).  The residuals are ``r = M e``, ``M = I - Z L Z^T``, ``Z``
    (3k, z) an orthonormal basis of the design's columns and of ``extra``
    ((3k, q), orthonormal and orthogonal to the design: directions also
    removed from the residuals, ``weight`` (q,) of each, default 1; the
    geometry's in :func:`_solve`), ``L`` diagonal, 1 on the design's
    directions and ``weight`` on ``extra``'s.  With ``D_j`` the (k, 3k) map
    of the residuals to component j's ``h`` (row k: ``P_k[j]`` on sample
    k's three rows) and ``K`` the window's band of ones, ``E[V_jj] = tr(K
    D_j M S M D_j^T)``, with ``Y = D_j Z L``:

        E[V_jj] = Omega_jj - 2 tr(K Y (D_j S Z)^T) + tr(K Y (Z^T S Z) Y^T),

    ``Omega = sum_k P_k (S P^T)_k``.  The expansion behind HC2's ``r_k^2 /
    (1 - h_kk)`` (unbiased for homoskedastic errors), carried over the
    window's cross products: the scores sum to zero (the normal
    equations), so each lag's sum is low by about the variance of the
    estimate -- with white errors ``(2 W + 1) Omega / k`` in all (``W =
    0``, one row a sample, equal leverages: ``k / (k - m)``).  The serial
    correlation is in the model because it changes the size of that loss:
    scores modulated by the motion's oscillation lose less over a long
    window than white ones, and the white model's factor overstated an
    AR(1) 0.8 std by 10 % on 200 samples.  Coverage it buys on
    100-2000-sample records: docs/design.md.  A factor of 1 where the
    model has no positive variance to correct (residuals all zero: an
    exact fit).
    """
    k, _, m = As3.shape
    P = np.einsum("mn,kin->kmi", bread, As3)  # (k, m, 3)
    Qa = _design_basis(As3.reshape(k * 3, m))
    Z, L = Qa, np.ones(Qa.shape[1])
    if extra is not None and extra.shape[1]:
        L = np.concatenate([L, np.ones(extra.shape[1]) if weight is None else weight])
        Z = np.hstack([Qa, extra])
    Z3 = Z.reshape(k, 3, -1)
    z = Z3.shape[2]
    SZ = _banded_times(Z3, r3, W)
    # P^T = Qa (Qa^T P^T): the influence rows lie in the design's span (bread is its pseudo-inverse)
    Pt = np.swapaxes(P, 1, 2).reshape(3 * k, m)
    SP = SZ[:, :, :Qa.shape[1]].reshape(3 * k, -1) @ (Qa.T @ Pt)
    omega = Pt.T @ SP
    omega = (omega + omega.T) / 2
    ZSZ = Z.T @ SZ.reshape(3 * k, z)
    expected = np.diag(omega).copy()
    for j in range(m):
        Pj = P[:, j, :, None]
        Y = np.sum(Pj * Z3, axis=1) * L  # (k, z)
        DSZ = np.sum(Pj * SZ, axis=1)
        expected[j] += np.sum((Y @ ZSZ - 2 * DSZ) * _window_sum(Y, W))
    ok = (np.diag(omega) > 0) & (expected > 0)
    return np.where(ok, np.diag(omega) / np.where(ok, expected, 1.0), 1.0)


def _banded_times(X: np.ndarray, r3: np.ndarray, W: int) -> np.ndarray:
    """(k, 3, q) ``S X`` for ``X`` (k, 3, q), ``S`` the working model's
    error covariance of :func:`_leverage_correction`: block ``(k, l)`` is
    ``C(k - l)`` for ``0 <= k - l <= W``, ``C(l - k)^T`` for ``0 < l - k
    <= W``, zero beyond; ``C(d) = sum_l r_{l+d} r_l^T / k`` (``r3`` (k, 3))."""
    k, _, q = X.shape
    Xt = np.ascontiguousarray(np.swapaxes(X, 0, 1)).reshape(3, k * q)  # columns (sample, column of X)
    out = (r3.T @ r3 / k) @ Xt
    for d in range(1, min(W, k - 1) + 1):
        C = r3[d:].T @ r3[:-d] / k
        out[:, d * q:] += C @ Xt[:, :-d * q]  # l = k - d: S_kl = C(d)
        out[:, :-d * q] += C.T @ Xt[:, d * q:]  # l = k + d: S_kl = C(d)^T
    return np.swapaxes(out.reshape(3, k, q), 0, 1)


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


ROUNDING_FLOOR = 1e-12
"""The absolute part of the excitation floor of :func:`_excited`: this
fraction of the largest gross torque about any axis (rounding, ~1e-16 of
it, amplified by the differentiation's 1e2-1e3, and a margin of 10).
Without it an axis about which the wires exert no torque at all had a zero
floor, and a column of rounding-level accelerations counted as excited
about it (session 20: the plate of thesis_plate_rest.yaml in torsion,
whose wires' gross torque about body y is exactly 0, gave Ixx 193.6 +- 5.3
for 208.3 once the 1 %-of-the-value rule no longer held it)."""


def _excited(scene: Scene, com, R, tensions, A2: np.ndarray, k: int) -> np.ndarray:
    """(m,) bool: whether each design column of ``A2`` ((3k, m), 1/s^2)
    carries, about some body axis, a torque above :data:`EXCITATION_FLOOR`
    of the gross wire torque about that axis (N m, RMS over the k samples)
    plus :data:`ROUNDING_FLOOR` of the largest axis's."""
    u = wire_units(scene, com, R)  # world, attachment -> anchor
    f_body = np.einsum("kji,knj->kni", R, tensions[..., None] * u)
    gross = np.abs(np.cross(scene.attachments[None, :, :], f_body)).sum(axis=1)  # (k, 3) N m
    g = np.sqrt(np.mean(gross ** 2, axis=0))  # (3,)
    floor = EXCITATION_FLOOR * g + ROUNDING_FLOOR * float(g.max())
    I_scale = float(np.max(np.linalg.eigvalsh(scene.inertia)))  # kg m^2
    A = A2.reshape(k, 3, -1)
    explained = I_scale * np.sqrt(np.mean(A ** 2, axis=0))  # (3, m) RMS over samples, N m
    return np.any(explained > floor[:, None], axis=0)

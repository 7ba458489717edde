"""Rigs of 4 or 5 nearly dependent wires at rest: how far the rigid model's
split can be trusted, and the split of elastic wires (session 15, elastic).

A level table on four vertical wires whose anchors are off by 0.1 .. 3 mm on
1 m wires has wires that are independent, but only just: the rigid model's
split of its weight then hangs on length differences smaller than the wires'
stretch under load (docs/design.md "elastic, session 15").

* :func:`length_strain_scale`: the relative length change (a strain) of one
  wire that moves the rigid split by a mean wire's load; where that is below
  :data:`PLAUSIBLE_STRAIN` (what lab wires stretch at their load), the rigid
  split is set by the wires' stretch, which the rigid model does not know;
* :func:`refuse_nearly_dependent`: the rest pose's refusal of such a rig
  where the rigid model would call a wire slack or pushing;
* :func:`elastic_rest` (:func:`elastic_rest_pose`, the rest pose's): the
  static equilibrium of the body on elastic, tension-only wires of axial stiffness ``EA`` (``rig.stiffness``, N), each
  a spring of stiffness ``EA_i / L_i`` beyond its length ``L_i``: Newton on
  the potential ``m g z + sum EA_i / (2 L_i) max(|d_i| - L_i, 0)^2`` over the
  pose, from the rigid rest pose.

SI units (N, m), world frame; poses as (com (3,), R (3, 3) body -> world).
"""

from __future__ import annotations

import numpy as np

from ..errors import BifilarError, ConvergenceError, SlackWireError, StiffnessNeededError, UnstableRestError
from ..rotations import rotvec_to_matrix
from ..scene import Scene, scene_with
from ..models.maximal import MAX_ELIMINATION_WIRES
from .equilibrium import (RestPose, _finish, _initial_pose, _newton_kkt, _raise_slack, _slsqp, constraint_hessians,
                          constraint_jacobian)

#: the largest strain a lab wire plausibly has at its load (steel or nylon wire, thread: 1e-5 .. 1e-3,
#: docs/design.md "offcentre, session 14"): a rig whose rigid split a length change of this size moves by
#: a mean wire's load is nearly dependent (:func:`length_strain_scale`)
PLAUSIBLE_STRAIN = 1e-3


def length_strain_scale(scene: Scene, com: np.ndarray, R: np.ndarray, lam: np.ndarray) -> float:
    """The strain ``e*`` (relative length change of one wire, ``dL_i / L_i``)
    that moves the rigid model's split by the mean load ``W / n`` of a wire
    (``W`` the weight), at a pose (com m, R body -> world) where every wire
    is at its length and ``lam`` (n,) N/m are the multipliers balancing the
    weight (negative ones allowed: the all-taut pose of a refused rig).

    First order: the KKT system ``[K G^T; G 0] [dx; dlam] = [0; L_i dL_i e_i]``
    (``K = sum lam_i H_i``) gives each wire's tension change
    ``dT = |d| dlam + lam dL`` for a length change of wire ``i``.  0 where
    the system is singular (dependent wires: the split is not set by the
    geometry at all).  Well-conditioned rigs give ~0.1 .. 1; a wire whose
    strain at load is above ``e*`` is stretched more than the length change
    that sets the split, so the rigid split is not the real one."""
    d, w, G = constraint_jacobian(scene, com, R)
    n = scene.n_wires
    ln = np.linalg.norm(d, axis=1)
    K = np.zeros((6 + n, 6 + n))
    K[:6, :6] = np.einsum("i,ijk->jk", lam, constraint_hessians(d, w))
    K[:6, 6:] = G.T
    K[6:, :6] = G
    L = np.asarray(scene.lengths, float)
    # dimensionless, as _newton_kkt: unknowns dr / L, dtheta, dlam L^2 / W; rows force / W, moment / (W L), phi / L^2
    W, Ls = scene.mass * scene.gravity, float(np.max(L))
    cs = np.concatenate([np.full(3, Ls), np.ones(3), np.full(n, W / Ls ** 2)])
    rs = np.concatenate([np.full(3, 1 / W), np.full(3, 1 / (W * Ls)), np.full(n, 1 / Ls ** 2)])
    A = rs[:, None] * K * cs[None, :]
    if np.linalg.cond(A) > 1e14:
        return 0.0
    rhs = np.zeros((6 + n, n))
    rhs[6:, :] = np.diag(L * L)  # d phi_i = -L_i dL_i, moved to the right: a unit strain dL_i = L_i per column
    sol = cs[:, None] * np.linalg.solve(A, rs[:, None] * rhs)
    dT = ln[:, None] * sol[6:, :] + np.diag(lam * L)  # (wire, strained wire): dT per unit strain
    worst = float(np.max(np.abs(dT)))
    return (W / n) / worst if worst > 0 else np.inf


def elastic_rest(scene: Scene, ea, com0: np.ndarray, R0: np.ndarray, iters: int = 60):
    """The static equilibrium of ``scene`` on elastic, tension-only wires of
    axial stiffness ``ea`` (N, scalar or (n,)): each wire a spring
    ``T_i = EA_i / L_i max(|d_i| - L_i, 0)``.  Newton on the potential's
    gradient in (dr, dtheta world) with the exact Hessian (the springs'
    ``k_i g_i g_i^T`` and their tensions' geometric term), each step halved
    until the potential falls, from the rigid pose (``com0`` m, ``R0``) moved
    down by the stretch the mean load gives the softest wire (every wire
    taut at the start), or from ``com0``, ``R0`` as they are where every
    wire is already stretched there (a neighbouring scene's elastic rest).  Returns (com (3,), R (3, 3), tensions (n,) N,
    residual: the largest force or moment / length left, per unit weight);
    :class:`~bifilar.errors.ConvergenceError` when Newton does not reach
    1e-10 of the weight (its rounding floor ~1e-12)."""
    L = np.asarray(scene.lengths, float)
    k = np.broadcast_to(np.asarray(ea, float), L.shape) / L  # N/m
    W = scene.mass * scene.gravity
    Ls = float(np.max(L))
    gradV = np.array([0.0, 0.0, W, 0.0, 0.0, 0.0])

    def state(c, R):
        d, w, G = constraint_jacobian(scene, c, R)
        ln = np.linalg.norm(d, axis=1)
        s = np.maximum(ln - L, 0.0)
        T = k * s
        energy = W * c[2] + 0.5 * float(np.sum(k * s * s))
        return d, w, G, ln, T, gradV + G.T @ (T / ln), energy

    scale = np.concatenate([np.full(3, 1.0 / W), np.full(3, 1.0 / (W * Ls))])
    xscale = np.concatenate([np.full(3, 1.0 / Ls), np.ones(3)])  # a step relative to the rig's size, rad
    c, R = np.asarray(com0, float), np.asarray(R0, float)
    d, w, G, ln, T, g, E = state(c, R)
    if not np.all(ln > L):  # a rigid pose (wires at their lengths): down by the stretch, every wire taut
        c = c - np.array([0.0, 0.0, (W / scene.n_wires) / float(np.min(k))])
        d, w, G, ln, T, g, E = state(c, R)
    # else a loaded pose (a neighbour's elastic rest, session 18): Newton from it, ~3 steps instead of ~8 from
    # the shifted one
    for _ in range(iters):
        if np.max(np.abs(g * scale)) < 1e-14:
            break
        taut = (ln > L).astype(float)
        lam = T / ln
        Gn = G / ln[:, None]
        # Hessian of the springs' energy: k (taut) g g^T / |d|^2 plus the tension's  lam (H_i - g g^T / |d|^2)
        H = np.einsum("i,ij,ik->jk", k * taut, Gn, Gn) + np.einsum("i,ijk->jk", lam, constraint_hessians(d, w)) \
            - np.einsum("i,ij,ik->jk", lam, Gn, Gn)
        H = 0.5 * (H + H.T)
        ev = np.linalg.eigvalsh(H)
        if ev[-1] <= 0.0:  # no wire taut (a step from a pose that overloads one wire lands above every length;
            # H = 0: the potential is W z there): straight down by the largest slack and the start's stretch
            # (a sigma point of four elastic wires, audit24: LinAlgError "Singular matrix", exit 1)
            x = np.array([0.0, 0.0, -(float(np.max(L - ln)) + (W / scene.n_wires) / float(np.min(k))), 0.0, 0.0, 0.0])
        else:
            if ev[0] <= 1e-12 * ev[-1]:  # not convex here (a wire slack, a neutral turn): shift to a descent step
                H = H + (1e-12 * ev[-1] - ev[0]) * np.eye(6)
            x = -np.linalg.solve(H, g)
        if np.max(np.abs(x) * xscale) < 1e-13 and np.max(np.abs(g * scale)) < 1e-12:
            break  # the step is rounding (the bifilar's floor 1.3e-14 of the weight sat above the 1e-14 aim: 60
            # rounding-sized steps, 20-50 ms, before session 18); nearly dependent wires take tiny steps at 1e-10
        for _half in range(40):
            c1, R1 = c + x[:3], rotvec_to_matrix(x[3:]) @ R
            st = state(c1, R1)
            if st[-1] <= E + 1e-15 * W * Ls:
                break
            x = 0.5 * x
        else:  # no step lowers the potential: at the rounding floor
            break
        c, R = c1, R1
        d, w, G, ln, T, g, E = st
    res = float(np.max(np.abs(g * scale)))
    if not res < 1e-10:
        raise ConvergenceError(f"elastic rest pose did not converge (residual {res:.2e} of the weight)")
    return c, R, T, res


def refuse_nearly_dependent(scene: Scene, idx, gap, c: np.ndarray, R: np.ndarray, lam: np.ndarray) -> None:
    """Raise :class:`~bifilar.errors.StiffnessNeededError` where the rigid
    model would refuse a rig of 4 or 5 wires for wires ``idx`` (0-based)
    slack by ``gap`` (m; None: at their length but pushing) although the
    wires are nearly dependent (:func:`length_strain_scale` ``e*`` at the
    all-taut pose ``c``, ``R`` with multipliers ``lam`` N/m below
    :data:`PLAUSIBLE_STRAIN`: a length change ``e* L``, less than a
    plausible stretch, moves the split by a wire's mean load) and each gap
    is below ``e* L`` (session 10's leaning table, its wire 4 slack by
    1.13 mm, ``e* L`` 0.6 mm, keeps its rigid verdict): there the rigid
    split, and whether a wire is slack, is set by length differences
    smaller than the wires' stretch under load, which no config without
    ``rig.stiffness`` states.  Returns otherwise."""
    if scene.n_wires <= MAX_ELIMINATION_WIRES:
        return
    L = np.asarray(scene.lengths, float)
    idx = [int(i) for i in idx]
    es = length_strain_scale(scene, c, R, lam)
    if not es < PLAUSIBLE_STRAIN:
        return
    if gap is not None and np.any(np.asarray(gap, float) >= es * L[idx]):
        return  # slack by more than the length change that moves the split by a wire's load: the rigid verdict
    d = c + scene.attachments @ R.T - scene.anchors
    T = lam * np.linalg.norm(d, axis=1)
    names = f"wire {idx[0] + 1}" if len(idx) == 1 else "wires " + ", ".join(str(i + 1) for i in idx)
    if gap is not None:
        how = f"slack by {np.max(gap) * 1000:.2g} mm"
    else:
        how = "pushing (" + ", ".join(f"{T[i]:.3g} N" for i in idx) + ")"
    load = scene.mass * scene.gravity / scene.n_wires
    raise StiffnessNeededError([i + 1 for i in idx], (
        f"on rigid wires {names} would be {how} at rest, but the {scene.n_wires} wires are nearly dependent: a change "
        f"of one wire's length by {es:.2g} of it ({es * float(np.max(L)) * 1000:.2g} mm) moves their rigid split by a "
        f"wire's mean load ({load:.3g} N), less than a loaded wire stretches (lab wires {PLAUSIBLE_STRAIN:g} of their "
        "length and less), so the split, and whether any wire is slack, is set by the wires' stretch, which the rigid "
        "model cannot say: give rig.stiffness (the wires' axial stiffness EA, N, one value or one per wire) for the "
        "elastic split"), gaps=None if gap is None else gap)


def elastic_rest_pose(scene: Scene, guess: RestPose | None) -> RestPose:
    """The rest pose of wires of axial stiffness ``scene.stiffness`` (EA, N;
    any number of wires since session 17, ``rig.lengths`` their unloaded
    lengths): the static equilibrium of elastic wires
    (:func:`~bifilar.analysis.elastic_rest.elastic_rest`), from the rigid
    pose with every wire at its length (2 or 3 wires: the rigid rest pose;
    4 or 5: Newton on the all-taut KKT equations from the start pose; or
    from ``guess``; SLSQP's pose where Newton fails).
    The pose is the elastic one (each wire stretched by ``T_i L_i / EA_i``,
    its wire vectors that long), its tensions the elastic split, exactly in
    equilibrium there, so the modes are the rigid model's about the loaded
    rig.  A wire the elastic wires leave slack is a
    :class:`~bifilar.errors.SlackWireError` (its gap the elastic one); an
    unstable one an :class:`~bifilar.errors.UnstableRestError` (the rigid
    model's checks, :func:`~bifilar.analysis.equilibrium._finish`)."""
    if guess is not None:
        c, R = guess.com.copy(), guess.R.copy()
        kkt = 0.0
    elif scene.n_wires <= MAX_ELIMINATION_WIRES:  # independent wires: the rigid rest (its checks, a line turn) starts it
        from .equilibrium import rest_pose

        rigid = rest_pose(scene_with(scene, stiffness=None))
        c, R = rigid.com.copy(), rigid.R.copy()
    else:
        try:
            c, R, _, kkt = _newton_kkt(scene, *_initial_pose(scene), iters=40)
        except np.linalg.LinAlgError:
            kkt = np.inf
        if not kkt < 1e-9:
            c, R, _, _ = _slsqp(scene, *_initial_pose(scene))
    try:
        return _elastic_finish(scene, c, R)
    except (UnstableRestError, SlackWireError) as err:
        if guess is not None or scene.n_wires <= MAX_ELIMINATION_WIRES:
            raise
        # the rigid all-taut pose of four or five nearly dependent wires can lie far off (a config 0.1 mm off a
        # square's four vertical 1.2 m wires: turned 49 deg, the CoM 1.2 m aside, the elastic rest from there
        # upside down, 'cannot hang in its start orientation', 3.5 % of such configs; on a pentagon's five a
        # wire 160 mm slack, 7 %: elastic25): the elastic Newton again from the start pose itself, which lowers
        # the body until every wire is taut; where that fails too, the first refusal (a real slack: the same)
        try:
            return _elastic_finish(scene, *_initial_pose(scene))
        except BifilarError:
            raise err from None


def _elastic_finish(scene: Scene, c: np.ndarray, R: np.ndarray) -> RestPose:
    """:func:`elastic_rest_pose` from the pose (``c`` m, ``R`` body -> world): the elastic rest and its checks."""
    c, R, T, res = elastic_rest(scene, scene.stiffness, c, R)
    d = c + scene.attachments @ R.T - scene.anchors
    ln = np.linalg.norm(d, axis=1)
    L = np.asarray(scene.lengths, float)
    slack = np.where(T <= 0.0)[0]
    if len(slack):
        _raise_slack(scene, slack, L[slack] - ln[slack], L)  # no advice: it is the rigid model's
    return _finish(scene, c, R, T / ln, res, phi_checked=False)


def loaded_scene(scene: Scene, rest: RestPose) -> Scene:
    """The scene the runs integrate: with a stated ``rig.stiffness`` the
    rigid-wire model on the loaded wires, each as long as it hangs at
    ``rest`` (the elastic rest pose, :func:`elastic_rest_pose`: ``|d_i|`` =
    ``L_i (1 + T_i / EA_i)``, m) and no stiffness (so nothing stretches
    them again); ``scene`` itself without one.  The run then starts on its
    wires at the rest pose the modes are taken about (docs/design.md
    "stretch, session 17": before, the runs held the wires at their unloaded
    lengths, 0.23 % off the 4-wire twin's period).  What the rigid run
    leaves out, the stretch's change with the swing's tension, is
    :func:`dynamic_stretch_warning`'s."""
    if scene.stiffness is None:
        return scene
    return scene_with(scene, lengths=np.linalg.norm(np.asarray(rest.wire_vectors, float), axis=1), stiffness=None)


def loaded_scenes(scenes, rests) -> list:
    """:func:`loaded_scene` of each (scene, rest) pair (a rest that is no
    :class:`RestPose`, a batch's error, leaves its scene as it is); one new
    scene for each distinct pair, so runs that share a scene and rest still
    share it (the batch groups them by identity)."""
    out, seen = [], {}
    for s, r in zip(scenes, rests):
        if s.stiffness is None or not isinstance(r, RestPose):
            out.append(s)
            continue
        key = (id(s), id(r))
        if key not in seen:
            seen[key] = loaded_scene(s, r)
        out.append(seen[key])
    return out


def elastic_hessian(scene: Scene, rest: RestPose) -> np.ndarray:
    """The Hessian (6, 6) of the elastic wires' potential (gravity's is
    linear in the pose) at ``rest`` in the (dr, dtheta world) chart of
    :func:`~bifilar.analysis.equilibrium.constraint_jacobian`: each taut
    wire's spring ``EA_i / L_i`` along its direction plus its tension's
    geometric term (:func:`elastic_rest`'s Hessian).  Units N/m, N, N m."""
    L = np.asarray(scene.lengths, float)
    k = np.asarray(scene.stiffness, float) / L
    d, w, G = constraint_jacobian(scene, rest.com, rest.R)
    ln = np.linalg.norm(d, axis=1)
    lam = np.asarray(rest.tensions, float) / ln
    Gn = G / ln[:, None]
    H = np.einsum("i,ij,ik->jk", k * (ln > L) - lam, Gn, Gn) + np.einsum("i,ijk->jk", lam, constraint_hessians(d, w))
    return 0.5 * (H + H.T)


def elastic_period_ratios(scene: Scene, rest: RestPose, modes) -> np.ndarray:
    """For each mode of ``modes`` (the linear modes about the elastic rest
    pose ``rest``: the rigid-wire model on the loaded wires), the ratio of
    the elastic wires' linear period to the mode's (NaN for a neutral mode):
    the full 6-coordinate eigenproblem of :func:`elastic_hessian` and the
    body's mass, its slowest ``len(modes)`` modes matched to ``modes`` by
    their shapes (kinetic-energy metric).  1 to rounding where the wires'
    stretch does not couple with the mode (a symmetric rig's torsion: the
    2 m trifilar of EA 1e5 N, 1 + 5e-8 by finite differences); a swing whose
    attachments sit above the CoM couples with the wires' tilt, a
    correction ~ the strain times the coupling (that trifilar's swings
    1 + 1.0e-4).  Dimensionless."""
    from scipy.linalg import eigh

    modes = list(getattr(modes, "modes", modes))
    if not modes:
        return np.zeros(0)
    M = np.zeros((6, 6))
    M[:3, :3] = scene.mass * np.eye(3)
    M[3:, 3:] = rest.R @ scene.inertia @ rest.R.T
    w2, V = eigh(elastic_hessian(scene, rest), M)
    k = len(modes)
    S = np.array([np.asarray(m.shape, float) for m in modes]).T  # (6, k)
    mac = (S.T @ M @ V[:, :k]) ** 2 / (np.einsum("ik,ij,jk->k", S, M, S)[:, None]
                                       * np.einsum("ik,ij,jk->k", V[:, :k], M, V[:, :k])[None, :])
    from scipy.optimize import linear_sum_assignment

    col = linear_sum_assignment(-mac)[1]
    out = np.full(k, np.nan)
    for j, m in enumerate(modes):
        if m.period and w2[col[j]] > 0:
            out[j] = (2 * np.pi / np.sqrt(w2[col[j]])) / m.period
    return out


#: a mode whose elastic linear period differs from the model's by more than this share of itself is warned
#: of (:func:`stretch_coupling_warning`): the seventh significant digit, which ``modes`` prints
COUPLING_REL = 1e-6


def stretch_coupling_warning(scene: Scene, rest: RestPose, modes, only=None) -> str | None:
    """With a stated ``rig.stiffness``, the warning naming the modes (all,
    or the one labelled ``only``) whose elastic linear period
    (:func:`elastic_period_ratios`; ``modes`` a ModeSet or a list of its
    modes) differs from the model's (rigid wires at
    their loaded lengths) by more than :data:`COUPLING_REL` of itself, or
    None."""
    if scene.stiffness is None:
        return None
    modes = list(getattr(modes, "modes", modes))
    ratio = elastic_period_ratios(scene, rest, modes)
    bad = [(m, r) for m, r in zip(modes, ratio)
           if np.isfinite(r) and abs(r - 1) > COUPLING_REL and (only is None or m.label == only)]
    if not bad:
        return None
    parts = ", ".join(f"{m.label} {r - 1:+.2g} ({m.period * r:.7g} s)" for m, r in bad)
    return ("rig.stiffness: the model's periods are the rigid wires' at their loaded lengths, but the wires' "
            f"stretch couples with the motion: the elastic wires' linear periods differ by {parts} of "
            "themselves; those modes' periods (and an inertia from them) are off by that much")


def dynamic_stretch_warning(scene: Scene, rest: RestPose, period, linear_period, period_error) -> str | None:
    """With a stated ``rig.stiffness``, the warning that a run's amplitude
    shift (``period - linear_period``, s) leaves out the stretch's change
    with the swing's tension, where its size, ~ the largest strain at rest
    times the shift, exceeds the run's ``period_error`` (s); None otherwise.
    Measured against elastic wires (a spring-law rigid body, the 2 m
    trifilar and its 4-wire twin of EA 1e5 N, strain 6.5e-3 / 4.9e-3,
    torsion at 0.02 .. 0.1 rad): the run's shift short by 1.1 x the strain
    of itself (0.1 rad: 5.1e-6 of the period, 7.1e-4 shift)."""
    if scene.stiffness is None or period is None or linear_period is None:
        return None
    strain = float(np.max(np.asarray(rest.tensions, float) / np.asarray(scene.stiffness, float)))
    err = strain * abs(period - linear_period)
    if not err > (period_error if np.isfinite(period_error) else 0.0):
        return None
    return (f"rig.stiffness: the run holds the wires at their loaded lengths; their stretch changes with the swing's "
            f"tension, which it leaves out: its amplitude shift ({period - linear_period:.3g} s) is short by about "
            f"the strain ({strain:.2g}) of itself, ~{err:.2g} s")

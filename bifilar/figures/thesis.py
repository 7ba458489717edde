"""The figures of ``docs/thesis.md``: one function per figure of
:mod:`bifilar.studies.reproduce`, each given the arrays that study computed
(SI units; time in s, angles in rad) and the path to write (PNG, cropped to
the drawn content)."""

from __future__ import annotations

import numpy as np

from . import new_figure, save


def _save(fig, path) -> None:
    save(fig, path, tight=True)


def spherical_pendulum(path, a: dict, b: dict) -> None:
    """Figs 4.5.2 and 4.5.3: the bob's path (m, world) by the angle form
    (``x``, 3 x k) and the constrained Cartesian form (``xc``) for the two
    starts ``a`` and ``b``."""
    fig = new_figure(size=(11, 4.6), axes=False)
    for k, (c, title) in enumerate(((a, "Fig 4.5.2: thetadot(0) = 1, phidot(0) = 2"),
                                    (b, "Fig 4.5.3: thetadot(0) = 1, phidot(0) = 0"))):
        ax = fig.add_subplot(1, 2, k + 1, projection="3d")
        ax.plot(*c["x"], lw=1.0, label="angles (4.5.7)")
        ax.plot(*c["xc"], "--", lw=0.8, label="Cartesian, constrained")
        ax.set_title(title)
        ax.set_xlabel("x (m)"), ax.set_ylabel("y (m)"), ax.set_zlabel("z (m)")
        if k == 0:
            ax.legend(fontsize=8)
    _save(fig, path)


def constraint_loop(path, poses: list) -> None:
    """Figs 5.1.2-5.1.3: the loop of vectors AB, BC, CD, AD (m, the thesis's
    n1, n2, n3) at each pose; ``poses``: (title, [(P0, P1, label, style), ...])."""
    fig = new_figure(size=(10, 4.6), axes=False)
    for k, (title, segments) in enumerate(poses):
        ax = fig.add_subplot(1, len(poses), k + 1, projection="3d")
        for P0, P1, lab, st in segments:
            ax.plot(*np.c_[P0, P1], st, lw=2, label=lab)
        ax.set_title(title, fontsize=10)
        ax.set_xlim(-1, 6), ax.set_ylim(-0.5, 10.5), ax.set_zlim(-5, 0.5)
        ax.set_xlabel("n1"), ax.set_ylabel("n2"), ax.set_zlabel("n3")
        ax.legend(fontsize=8)
    _save(fig, path)


def side_sway(path, t, theta2, theta3, crossings, rel, T_sim: float, T_exact: float, T_small: float) -> None:
    """Section 6.1 / Fig 6.1.1: theta2, theta3 (rad) against t with the
    upward crossings that timed the period (s); the relation
    5 sin(pi/6)/cos(theta3 - pi/2) - 5 sin(theta2) (m)."""
    fig, axs = new_figure(1, 2, size=(11, 3.6))
    axs[0].plot(t, theta2, label="θ2")
    axs[0].plot(t, theta3, label="θ3")
    for tc in crossings:
        axs[0].axvline(tc, color="0.8", lw=0.6)
    axs[0].set_xlabel("t (s)"), axs[0].set_ylabel("rad"), axs[0].legend()
    axs[0].set_title(f"side sway, θ̇3(0) = 1 rad/s: period {T_sim:.5f} s (exact {T_exact:.5f}, "
                     f"small-angle {T_small:.4f})", fontsize=9)
    axs[1].plot(t, rel)
    axs[1].set_xlabel("t (s)"), axs[1].set_ylabel("m")
    axs[1].set_title("5 sin(π/6)/cos(θ3 − π/2) − 5 sin θ2 (thesis: mean −2.05e-7)", fontsize=9)
    _save(fig, path)


def torsion(path, geometry: str, model_label: str, cases: list) -> None:
    """Section 6.2: rotation about the vertical (rad) against t (s) by the
    full model and a thesis model; ``cases``: (amplitude label, case) with
    ``t``, ``yaw``, ``yaw_model`` and the period error ``err`` (1)."""
    fig, axs = new_figure(1, len(cases), size=(11, 3.6))
    for ax, (amp, c) in zip(np.atleast_1d(axs), cases):
        ax.plot(c["t"], c["yaw"], label="full model (default)")
        ax.plot(c["t"], c["yaw_model"], "--", label=model_label)
        ax.set_xlabel("t (s)"), ax.set_ylabel("rotation about the vertical (rad)")
        ax.set_title(f"{geometry} wires, θ0 = {amp}: period error {100 * c['err']:+.3f} %", fontsize=9)
        ax.legend(fontsize=8)
    _save(fig, path)


def double_pendulum(path, t, full, exact, analogy, theta1: float) -> None:
    """Fig 6.3.2: phi2, the roll about CD (rad), by the full model, the exact
    planar reduction and the thesis's analogy, and their differences."""
    fig, axs = new_figure(1, 2, size=(11, 3.6))
    axs[0].plot(t, full, label="full model")
    axs[0].plot(t, exact, "--", label="exact reduction (m1 = 0, I2 = I_CD)")
    axs[0].plot(t, analogy, ":", label="thesis analogy (m1 = m2 = 5)")
    axs[0].set_xlabel("t (s)"), axs[0].set_ylabel("φ2 = roll about CD (rad)"), axs[0].legend(fontsize=8)
    axs[0].set_title(f"Fig 6.3.2: θ1(0) = {theta1} rad", fontsize=9)
    axs[1].semilogy(t, np.maximum(np.abs(np.asarray(exact) - full), 1e-17), label="|exact reduction − full|")
    axs[1].semilogy(t, np.maximum(np.abs(np.asarray(analogy) - full), 1e-17), label="|analogy − full|")
    axs[1].set_xlabel("t (s)"), axs[1].set_ylabel("rad"), axs[1].legend(fontsize=8)
    _save(fig, path)


def double_pendulum_starts(path, t, phi2_a, phi2_b) -> None:
    """Fig 6.3.3: the thesis's double pendulum, phi2 (rad) from two starts."""
    fig, ax = new_figure(size=(6.5, 3.4))
    ax.plot(t, phi2_a, label="φ(0) = [0, π/6]")
    ax.plot(t, phi2_b, "--", label="φ(0) = [0.05, π/6]")
    ax.set_xlabel("t (s)"), ax.set_ylabel("φ2 (rad)"), ax.legend(fontsize=8)
    ax.set_title("Fig 6.3.3: the thesis's double pendulum from two starts", fontsize=9)
    _save(fig, path)


def cylinder(path, t, panels: list) -> None:
    """Figs 6.4.2-6.4.4: each quantity by the Kane model and the default
    model against the dimensionless time t sqrt(g/b); ``panels``:
    (kane, default, label)."""
    fig, axs = new_figure(1, len(panels), size=(13, 3.4))
    for ax, (a, b, lab) in zip(axs, panels):
        ax.plot(t, a, label="Kane (thesis) model")
        ax.plot(t, b, "--", label="default model")
        ax.set_xlabel("t √(g/b)"), ax.set_title(lab, fontsize=9)
    axs[0].legend(fontsize=8)
    _save(fig, path)


def linearisation(path, errors: list) -> None:
    """Table 7.1.1: the error (%) of each estimate of the three
    linearisations; ``errors``: per linearisation, the errors of the thesis's
    printed value, the thesis's method, the exact linear and the nonlinear
    estimate (NaN where not applicable)."""
    from matplotlib.patches import Rectangle

    fig, ax = new_figure(size=(7.5, 3.4))
    meths = ("thesis (printed)", "thesis method", "exact linear", "nonlinear")
    for j, errs in enumerate(errors):
        ax.bar(np.arange(4) + 5 * j, errs, color=["C3", "C0", "C1", "C2"])
    ax.set_xticks([1.5, 6.5, 11.5], ["Lin. 1 (I1)", "Lin. 2 (I2)", "Lin. 3 (I3)"])
    ax.axhline(0, color="k", lw=0.6)
    ax.set_ylabel("error of the estimate (%)")
    ax.legend([Rectangle((0, 0), 1, 1, color=f"C{i}") for i in (3, 0, 1, 2)], meths, fontsize=8)
    ax.set_title("Table 7.1.1: inertia from the period simulated at π/80", fontsize=9)
    _save(fig, path)


def tensions(path, t, model, general, symmetric, t_literal, literal, rest: float, yaw, rise) -> None:
    """Fig 7.2.2: the wire tension (N) of a torsion by the model's
    multipliers and the thesis's two formulas, and of the literal start
    (``t_literal``, ``literal``); below, the rotation about the vertical (rad)
    and the CoM rise (m) against t (s)."""
    fig, axs = new_figure(2, 1, size=(8, 5.2), sharex=True)
    axs[0].plot(t, model, lw=2.5, alpha=0.5, label="model multipliers (both wires)")
    axs[0].plot(t, general, "--", label="thesis general least squares")
    axs[0].plot(t, symmetric, ":", label="thesis symmetric formula")
    axs[0].plot(t_literal, literal, lw=0.8, color="0.5", label="wire 1, literal θ4-only start")
    axs[0].axhline(rest, color="0.5", lw=0.6)
    axs[0].set_ylabel("tension (N)"), axs[0].legend(fontsize=7)
    axs[0].set_title("Fig 7.2.2: thin plate, torsion from π/12 (grey line: at rest)", fontsize=9)
    axs[1].plot(t, yaw, label="rotation about the vertical (rad)")
    axs[1].plot(t, 20 * np.asarray(rise), label="20 x CoM rise (m)")
    axs[1].set_xlabel("t (s)"), axs[1].legend(fontsize=7)
    _save(fig, path)


def solar_tensions(path, runs: list, labels: list | None = None) -> None:
    """Fig 8.4.1: tension per wire (N) against t (s) of each Solar Boat
    configuration; ``runs``: (t, tension, rest tension); ``labels``: one per
    run (default "configuration 1", ...)."""
    fig, ax = new_figure(size=(8, 3.6))
    for ci, (t, T, T0) in enumerate(runs, start=1):
        ax.plot(t, T, color=f"C{ci - 1}", label=labels[ci - 1] if labels else f"configuration {ci}")
        ax.axhline(T0, color=f"C{ci - 1}", lw=0.7, ls="--")
    ax.set_xlabel("t (s)"), ax.set_ylabel("tension per wire (N)"), ax.legend(fontsize=8)
    ax.set_title("Fig 8.4.1: Solar Boat, θ4(0) = π/12 torsion (dashed: at rest)", fontsize=9)
    _save(fig, path)

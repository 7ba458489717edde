"""Several evaluations' batched calls in one batch: the rest poses and modes
of the honest budget's sigma-point scenes and the nonlinear runs' start
poses of many sweep points, each taken in one call of the batched engine
for all of them, so its numpy call overhead (hundreds of calls on small
stacked arrays: ~0.9 ms and ~1.1 ms a Solar Boat point, docs/design.md
"sigbatch29") is paid once for the chunk instead of once a point.

How.  :func:`run_together` runs each evaluation (a whole sweep point,
:func:`bifilar.studies.point.evaluate_point`) in a thread of its own, one
thread at a time (a turn handed over by one event a thread: never two
running, so what each does happens in its own order alone).  Where an evaluation
reaches a shareable call it asks :func:`shared` and parks; when every
evaluation has parked or finished, the parked requests of each kind are
solved in one batch (:data:`SOLVERS`) and each evaluation resumes with
its own rows.  Outside :func:`run_together`, :func:`shared` answers None
and the caller computes its own batch, as always.

Why a point's figures stay its own, bit for bit.  Each row of these
batches is computed from that row only: the batched Newton of
:func:`~bifilar.analysis.batch_rest.rest_poses` freezes a scene's row when
its own residual converges, :func:`~bifilar.analysis.start_pose.start_poses`
iterates row by row, and every stacked call (einsum, ``np.linalg.solve``,
``svd``, ``eigh``, matmul on (B, k, k)) computes a slice from that slice
(checked: the 1008 sigma-point scenes and the 252 start poses of the
28-point boat sweep, batched per point against all in one batch, the same
bytes, also under ``OPENBLAS_CORETYPE=Sandybridge`` and ``Haswell``;
``tests/test_sigbatch29.py`` compares whole points field by field).  What
is decided per point is not shared: a sigma-point request is answered
only where every scene of it is accepted from the start pose's Newton
(none needs the per-point ``near`` pose, the global search or the elastic
statics); a request with any other scene, every request where the scenes
have several wire counts, and every one where the shared modes fail, get
None and compute their own batch as they would alone.
Units: none here (scenes, poses and amplitudes SI, as the engine's).
"""

from __future__ import annotations

import threading
from typing import Callable, Sequence

_local = threading.local()


class _Aborted(BaseException):
    """An evaluation stopped because :func:`run_together` was left early (Ctrl-C)."""


class _Turns:
    """Who runs: evaluation ``i`` while its event ``go[i]`` is set, the
    calling thread while ``back`` is (one event a thread, so a hand-over
    wakes only the thread it is for); parked requests {index: (kind,
    payload)} and their answers."""

    def __init__(self, n: int):
        self.go = [threading.Event() for _ in range(n)]
        self.back = threading.Event()
        self.parked: dict[int, tuple] = {}
        self.answers: dict[int, object] = {}
        self.abort = False

    def wait_turn(self, i: int) -> None:
        self.go[i].wait()
        if self.abort:
            raise _Aborted()

    def hand_back(self, i: int) -> None:
        self.go[i].clear()
        self.back.set()

    def park(self, i: int, request: tuple):
        self.parked[i] = request
        self.hand_back(i)
        self.wait_turn(i)
        return self.answers.pop(i)

    def step(self, i: int) -> None:
        """Let evaluation ``i`` run until it parks or finishes."""
        self.back.clear()
        self.go[i].set()
        self.back.wait()

    def stop(self) -> None:
        self.abort = True
        for g in self.go:
            g.set()


def shared(kind: str, payload):
    """The answer to ``payload`` (a request of ``kind``, a key of
    :data:`SOLVERS`) from a batch shared with the other evaluations of
    :func:`run_together`: what the caller's own batch gives, the same
    numbers; None outside one, or where the shared batch cannot give
    exactly that (the caller then computes its own)."""
    turns = getattr(_local, "turns", None)
    if turns is None:
        return None
    return turns.park(_local.index, (kind, payload))


def _sigma_points(requests: list[list]) -> list:
    """Each request's (rest poses, mode sets) of its scenes (one hanging's
    sigma-point scenes: :func:`~bifilar.analysis.batch_rest.rest_poses`
    with ``defer``, then :func:`~bifilar.analysis.batch_rest.modes_batch`
    ``lazy``), from one batch of all their scenes; None for a request
    whose answer there is not its own (module docstring)."""
    import numpy as np

    from ..errors import BifilarError
    from .batch_rest import modes_batch, rest_poses

    scenes = [s for r in requests for s in r]
    none = [None] * len(requests)
    spans, j = [], 0
    for r in requests:
        spans.append((j, j + len(r)))
        j += len(r)
    geo: list = []
    try:
        rs = rest_poses(scenes, None, errors="return", geometry=geo, defer=True)
    except (BifilarError, np.linalg.LinAlgError):
        return none
    if not geo:
        return none  # several wire counts (rest_poses by group)
    ok = geo[0].ok
    # a request with a scene not accepted from the start pose: its own batch (the near pose, the global search
    # or the elastic statics, each per point)
    mine = [n for n, (a, b) in enumerate(spans) if bool(np.all(ok[a:b]))]
    if not mine:
        return none
    rows = [q for n in mine for q in range(*spans[n])]
    try:
        if len(mine) == len(requests):
            mss = modes_batch(scenes, rs, lazy=True, geometry=geo[0])
        else:  # (the geometry holds every row: without it, the same expressions on the poses)
            mss = modes_batch([scenes[q] for q in rows], [rs[q] for q in rows], lazy=True)
    except (BifilarError, np.linalg.LinAlgError):
        return none  # each point's own batch decides which of its scenes' modes fail
    out, k = list(none), 0
    for n in mine:
        a, b = spans[n]
        out[n] = (rs[a:b], mss[k:k + b - a])
        k += b - a
    return out


def _start_poses(requests: list[tuple]) -> list:
    """Each request's :class:`~bifilar.analysis.start_pose.StartPoses`
    ((scenes, rests, modes, amplitudes (B,)) of
    :func:`~bifilar.analysis.start_pose.start_poses`) from one call for all
    of them (rows solved independently); None for all where their scenes
    have several wire counts."""
    import numpy as np

    from .start_pose import start_poses

    if len({len(s.lengths) for r in requests for s in r[0]}) != 1:
        return [None] * len(requests)
    sp = start_poses([s for r in requests for s in r[0]], [x for r in requests for x in r[1]],
                     [m for r in requests for m in r[2]], np.concatenate([r[3] for r in requests]))
    out, j = [], 0
    for r in requests:
        out.append(sp.take(np.arange(j, j + len(r[0]))))
        j += len(r[0])
    return out


#: kind -> solver: [payload, ...] -> [answer or None, ...]
SOLVERS: dict[str, Callable[[list], list]] = {"sigma points": _sigma_points, "start poses": _start_poses}


def run_together(fns: Sequence[Callable[[], object]], on_done: Callable[[int, object], None] | None = None) -> list:
    """The values of ``fns`` (in order), each run in a thread of its own,
    one at a time, their :func:`shared` requests solved together by kind
    (module docstring).  ``on_done(i, value)`` is called in the calling
    thread as each finishes.  An exception of a function (KeyboardInterrupt
    included) is raised here, after stopping the others (each at its next
    request); so is a KeyboardInterrupt of the calling thread."""
    n = len(fns)
    turns = _Turns(n)
    out: list = [None] * n
    done = [False] * n
    failed: list = []

    def body(i: int) -> None:
        _local.turns, _local.index = turns, i
        try:
            turns.wait_turn(i)
            out[i] = fns[i]()
        except _Aborted:
            pass
        except BaseException as exc:  # noqa: BLE001 - handed to the calling thread, raised there
            failed.append(exc)
        finally:
            done[i] = True
            turns.hand_back(i)

    def step(i: int) -> None:
        turns.step(i)
        if failed:
            raise failed[0]
        if done[i] and on_done is not None:
            on_done(i, out[i])

    threads = [threading.Thread(target=body, args=(i,), daemon=True, name=f"bifilar-shared-{i}") for i in range(n)]
    for t in threads:
        t.start()
    try:
        for i in range(n):
            step(i)
        while turns.parked:
            ids = sorted(turns.parked)
            for kind in dict.fromkeys(turns.parked[i][0] for i in ids):  # each kind in one batch, in a fixed order
                mine = [i for i in ids if turns.parked[i][0] == kind]
                try:
                    answers = SOLVERS[kind]([turns.parked[i][1] for i in mine])
                except Exception:  # noqa: BLE001 - each request its own batch: the error it gives alone, if any
                    answers = [None] * len(mine)
                for i, a in zip(mine, answers):
                    turns.answers[i] = a
            for i in ids:
                del turns.parked[i]
                step(i)
    except BaseException:
        turns.stop()
        raise
    for t in threads:
        t.join()
    return out

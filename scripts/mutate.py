"""Mutation testing of one module at a time (docs/mutation.md): does the
suite notice when the code is broken on purpose?

Each mutant changes one token of MODULE: a binary operator (+ <-> -, * <-> /,
** -> *, < <-> <=, > <-> >=, == <-> !=), a unary minus dropped, a number
(0 -> 1, an integer + 1, a float x 2, the quantiles 0.975 -> 0.95 and
0.025 -> 0.05), and/or swapped, True/False swapped.  Docstrings, comments
and import lines are left alone.  For each mutant the given test files run
(``pytest -x``, no xdist) in a private copy of the repo under /tmp/mut (so
the worktree is never touched, and workers run in parallel); exit 0 means
the mutant SURVIVED.  A mutant on a line the tests never execute (found by
one traced run of the unmutated tests) is recorded ``uncovered`` without a
run.  Results go to OUT.jsonl, one record per mutant.

Usage (from the repo root; dev tool, not a dependency):

    python scripts/mutate.py bifilar/analysis/tensions.py /tmp/tensions.jsonl \
        --tests tests/test_tensions.py tests/test_coverage_tensions.py --workers 2
    python scripts/mutate.py --report /tmp/tensions.jsonl

``--stride N`` runs every N-th mutant (a sample), ``--ids`` chosen ones
(e.g. the survivors again, with a new test file); extra pytest options
through the PYTEST_ADDOPTS environment variable (e.g. ``--deselect``).
``--no-trace``: run every mutant, none counted ``uncovered`` -- for tests
that run the code in a subprocess (``python -m bifilar ...``), which the
in-process trace does not see (the baseline still runs once and must pass).
"""
import argparse, io, json, os, shutil, subprocess, sys, time, tokenize, keyword
from concurrent.futures import ThreadPoolExecutor

BINOP = {"+": "-", "-": "+", "*": "/", "/": "*", "**": "*", "<": "<=", "<=": "<", ">": ">=", ">=": ">",
         "==": "!=", "!=": "==", "//": "/", "%": "*"}
SPECIAL_NUM = {"0.975": "0.95", "0.025": "0.05", "0.95": "0.9", "0.05": "0.1"}


def mutants(src):
    toks = list(tokenize.generate_tokens(io.StringIO(src).readline))
    lines = src.splitlines(keepends=True)
    out = []
    depth_def = False
    for i, t in enumerate(toks):
        prev = toks[i - 1] if i else None
        nxt = toks[i + 1] if i + 1 < len(toks) else None
        if t.start[0] > len(lines):
            continue
        line = lines[t.start[0] - 1]
        if line.lstrip().startswith(("import ", "from ")):
            continue
        new = None
        if t.type == tokenize.OP and t.string in BINOP:
            s = t.string
            unary_ctx = prev is None or (prev.type == tokenize.OP and prev.string in "([{,=:" ) or \
                (prev.type == tokenize.OP and prev.string in ("+", "-", "*", "/", "**", "<", ">", "<=", ">=", "==")) or \
                (prev.type == tokenize.NAME and prev.string in ("return", "and", "or", "not", "in", "if", "else", "lambda", "yield"))
            if s in ("*", "**") and (unary_ctx or (nxt is not None and nxt.type == tokenize.OP and nxt.string in ",)")):
                continue  # unpacking / keyword-only marker
            if s == "-" and unary_ctx:
                out.append((t.start, t.end, "", "drop unary -"))
                continue
            if s == "+" and unary_ctx:
                continue
            new = BINOP[s]
            out.append((t.start, t.end, new, f"{s} -> {new}"))
        elif t.type == tokenize.NUMBER:
            s = t.string
            if s in SPECIAL_NUM:
                new = SPECIAL_NUM[s]
            else:
                try:
                    v = eval(s)
                except Exception:
                    continue
                if isinstance(v, complex):
                    continue
                if v == 0:
                    new = "1"
                elif isinstance(v, int):
                    new = str(v + 1)
                else:
                    new = repr(v * 2)
            out.append((t.start, t.end, new, f"{s} -> {new}"))
        elif t.type == tokenize.NAME and t.string in ("and", "or", "True", "False"):
            new = {"and": "or", "or": "and", "True": "False", "False": "True"}[t.string]
            out.append((t.start, t.end, new, f"{t.string} -> {new}"))
    return out


def apply(src, m):
    lines = src.splitlines(keepends=True)
    (r0, c0), (r1, c1), new, _ = m
    assert r0 == r1
    L = lines[r0 - 1]
    lines[r0 - 1] = L[:c0] + new + L[c1:]
    return "".join(lines)


def setup_worker(root, n, tag="w"):
    w = f"/tmp/mut/{tag}{n}"
    if os.path.exists(w):
        shutil.rmtree(w)
    shutil.copytree(root, w, ignore=shutil.ignore_patterns(".git", "__pycache__", "*.pyc", ".pytest_cache"))
    if not os.path.exists("/tmp/mut/shared"):
        os.symlink(os.path.join(os.path.dirname(os.path.abspath(root)), "shared"), "/tmp/mut/shared")
    return w


def run_tests(w, tests, timeout):
    env = dict(os.environ, PYTHONPATH=w, PYTHONDONTWRITEBYTECODE="1", OMP_NUM_THREADS="1",
               OPENBLAS_NUM_THREADS="1", MKL_NUM_THREADS="1")
    t0 = time.time()
    try:
        p = subprocess.run([sys.executable, "-m", "pytest", "-x", "-q", "-p", "no:cacheprovider",
                            "-p", "no:xdist", "-p", "no:benchmark", *tests], cwd=w, env=env,
                           capture_output=True, text=True, timeout=timeout)
        rc = p.returncode
        tail = [l for l in p.stdout.splitlines() if l.startswith(("FAILED", "ERROR"))][:1]
    except subprocess.TimeoutExpired:
        rc, tail = "timeout", []
    return rc, time.time() - t0, (tail[0] if tail else "")


COVER = r'''
import sys, json, threading
TARGET = sys.argv[1]; OUT = sys.argv[2]
hit = set()
def tr(frame, event, arg):
    if frame.f_code.co_filename != TARGET:
        return None
    def lt(f, e, a):
        if e == "line": hit.add(f.f_lineno)
        return lt
    hit.add(frame.f_lineno)
    return lt
sys.settrace(tr); threading.settrace(tr)
import pytest
rc = pytest.main(["-q", "-p", "no:cacheprovider", "-p", "no:xdist", "-p", "no:benchmark", *sys.argv[3:]])
sys.settrace(None)
json.dump(sorted(hit), open(OUT, "w"))
sys.exit(rc)
'''


def covered_lines(w, module, tests):
    open("/tmp/mut/cover.py", "w").write(COVER)
    target = os.path.join(w, module)
    out = f"{w}.cov.json"
    env = dict(os.environ, PYTHONPATH=w, PYTHONDONTWRITEBYTECODE="1")
    p = subprocess.run([sys.executable, "/tmp/mut/cover.py", target, out, *tests], cwd=w, env=env,
                       capture_output=True, text=True)
    if p.returncode != 0:
        print(p.stdout[-3000:], p.stderr[-3000:])
        raise SystemExit("baseline tests fail")
    return set(json.load(open(out)))


def report(paths):
    """Counts per file and the mutants not killed."""
    import collections

    for f in paths:
        r = {}
        for line in open(f):
            x = json.loads(line)
            r[x["id"]] = x
        c = collections.Counter("killed" if x["status"].startswith("killed") else x["status"] for x in r.values())
        print(f, len(r), dict(c))
        for x in sorted(r.values(), key=lambda x: x["id"]):
            if not x["status"].startswith("killed"):
                print(f'  {x["id"]:4d} L{x["line"]:<4d} {x["status"]:9s} {x["desc"]:28s} | {x["code"][:100]}')


def main():
    if len(sys.argv) > 1 and sys.argv[1] == "--report":
        return report(sys.argv[2:])
    ap = argparse.ArgumentParser()
    ap.add_argument("module"); ap.add_argument("out")
    ap.add_argument("--tests", nargs="+", required=True)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--lines", default=None, help="a-b: only mutate these lines")
    ap.add_argument("--timeout", type=float, default=None)
    ap.add_argument("--tag", default="w")
    ap.add_argument("--stride", type=int, default=1)
    ap.add_argument("--skip", default="", help="comma list of ids already run")
    ap.add_argument("--ids", default=None, help="comma list of mutant ids to (re)run")
    ap.add_argument("--no-trace", action="store_true",
                    help="count every line covered (tests that run the module in a subprocess)")
    a = ap.parse_args()
    root = os.getcwd()
    src = open(os.path.join(root, a.module)).read()
    ms = mutants(src)
    if a.lines:
        lo, hi = map(int, a.lines.split("-"))
        ms = [m for m in ms if lo <= m[0][0] <= hi]
    ids = list(range(len(ms)))
    ids = ids[::a.stride]
    if a.skip:
        ids = [i for i in ids if i not in {int(x) for x in a.skip.split(",")}]
    if a.ids:
        ids = [int(x) for x in a.ids.split(",")]
    ws = [setup_worker(root, n, a.tag) for n in range(a.workers)]
    t0 = time.time()
    cov = covered_lines(ws[0], a.module, a.tests)
    if a.no_trace:
        cov = set(range(1, len(src.splitlines()) + 1))
    base = time.time() - t0
    timeout = a.timeout or max(3 * base + 20, 60)
    print(f"{len(ms)} mutants, {len(cov)} covered lines, baseline+trace {base:.1f}s, timeout {timeout:.0f}s", flush=True)
    results = []
    lines = src.splitlines()

    def job(i, w):
        m = ms[i]
        rec = {"id": i, "line": m[0][0], "col": m[0][1], "desc": m[3], "code": lines[m[0][0] - 1].strip()}
        if m[0][0] not in cov:
            rec.update(status="uncovered", secs=0)
            return rec
        msrc = apply(src, m)
        try:
            compile(msrc, a.module, "exec")
        except SyntaxError:
            rec.update(status="invalid", secs=0)
            return rec
        path = os.path.join(w, a.module)
        open(path, "w").write(msrc)
        try:
            rc, secs, why = run_tests(w, a.tests, timeout)
        finally:
            open(path, "w").write(src)
        status = {0: "survived", 1: "killed", "timeout": "killed (timeout)"}.get(rc, f"killed (rc {rc})")
        rec.update(status=status, secs=round(secs, 1), by=why)
        return rec

    from queue import Queue
    free = Queue()
    for w in ws:
        free.put(w)

    def run(i):
        w = free.get()
        try:
            return job(i, w)
        finally:
            free.put(w)

    with open(a.out, "a") as f, ThreadPoolExecutor(len(ws)) as ex:
        for rec in ex.map(run, ids):
            f.write(json.dumps(rec) + "\n"); f.flush()
            if rec["status"] not in ("killed",):
                print(rec["id"], rec["line"], rec["desc"], rec["status"], "|", rec["code"][:90], flush=True)
    print(f"done in {time.time() - t0:.0f}s")


if __name__ == "__main__":
    main()

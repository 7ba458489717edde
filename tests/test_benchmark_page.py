"""scripts/run_benchmarks.py regenerates docs/performance.md but keeps the
hand-written record of each session's measurements (the paragraphs between
``<!-- hand-written -->`` markers), each under the heading it followed."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "scripts"))

from run_benchmarks import HAND_CLOSE, HAND_OPEN, keep_hand_written  # noqa: E402

NEW = "# Page\n\nnew intro\n\n## A\n\nnew a\n\n### A1\n\nnew a1\n\n## B\n\nnew b\n\n## Reproduce\n\nrun it\n"


def _block(text: str) -> str:
    return f"{HAND_OPEN}\n{text}\n{HAND_CLOSE}"


def test_blocks_stay_under_their_heading_and_generated_text_is_replaced():
    old = (f"# Page\n\nold intro\n\n## A\n\nold a\n\n{_block('record a, session 6')}\n\n### A1\n\nold a1\n\n"
           f"{_block('### Hand heading' + chr(10) + 'record under a hand heading')}\n\n## B\n\nold b\n"
           f"{_block('record b')}\n\n## Reproduce\n\nrun it\n")
    out = keep_hand_written(old, NEW)
    assert "old " not in out
    for text in ("new intro", "new a\n", "new a1", "new b", "record a, session 6", "### Hand heading", "record b"):
        assert out.count(text) == 1, text
    pos = {t: out.index(t) for t in ("new a\n", "record a, session 6", "### A1", "new a1", "### Hand heading",
                                       "## B", "new b", "record b", "## Reproduce")}
    order = sorted(pos, key=pos.get)
    assert order == ["new a\n", "record a, session 6", "### A1", "new a1", "### Hand heading", "## B", "new b",
                     "record b", "## Reproduce"]
    # the heading inside a block is not a section of its own: the next block still anchors on "## B"
    assert out.count(HAND_OPEN) == out.count(HAND_CLOSE) == 3


def test_a_block_whose_heading_is_gone_is_kept_before_reproduce():
    old = f"# Page\n\n## Gone\n\n{_block('orphan record')}\n\n## Reproduce\n"
    out = keep_hand_written(old, NEW)
    assert out.index("orphan record") < out.index("## Reproduce")
    assert out.index("orphan record") > out.index("new b")


def test_a_page_without_blocks_is_the_generated_one():
    assert keep_hand_written("# Page\n\nold\n", NEW) == NEW


@pytest.mark.parametrize("old", [f"{HAND_OPEN}\nnever closed\n", f"{HAND_CLOSE}\n",
                                 f"{HAND_OPEN}\n{HAND_OPEN}\nx\n{HAND_CLOSE}\n"])
def test_broken_markers_are_refused_rather_than_losing_a_record(old):
    with pytest.raises(ValueError):
        keep_hand_written(old, NEW)


def test_the_shipped_page_keeps_every_session_record():
    """Every paragraph of docs/performance.md that the script does not
    write is inside a block: regenerating the page from its own headings
    keeps all the session paragraphs (the page's text outside blocks is
    replaced by a placeholder here)."""
    page = (ROOT / "docs" / "performance.md").read_text()
    heads = [ln for ln in page.splitlines() if ln.startswith("#")]
    inside, kept = False, []
    for ln in page.splitlines():
        if ln.strip() == HAND_OPEN:
            inside = True
        elif ln.strip() == HAND_CLOSE:
            inside = False
        elif inside:
            kept.append(ln)
    generated_heads = [h for h in heads if h not in kept]
    fake_new = "\n\n".join(f"{h}\n\nx" for h in generated_heads) + "\n"
    out = keep_hand_written(page, fake_new)
    for ln in page.splitlines():
        if ln.startswith("**Session"):
            assert ln in out, ln[:60]

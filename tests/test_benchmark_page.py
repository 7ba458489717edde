"""scripts/run_benchmarks.py regenerates docs/performance.md but keeps the
hand-written record of each session's measurements (the paragraphs between
``<!-- hand-written -->`` markers), each under the heading it followed."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "scripts"))

from run_benchmarks import HAND_CLOSE, HAND_OPEN, I14_HEADING, I14_OLD_HEADINGS, keep_hand_written, splice_issue14  # noqa: E402,E501

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


def test_issue14_only_replaces_that_section_and_keeps_the_rest():
    """``--issue14-only`` re-measures one section: the other sections stay as
    the last full run wrote them, every hand-written block stays where it was
    (also under the section's heading as the page had it before the sweep
    figures were added), and the section's old generated text is gone."""
    old = (f"# Page\n\nintro kept\n\n## A\n\na kept\n\n{_block('record a')}\n\n"
           f"{I14_OLD_HEADINGS[0]}\n\nold i14 text\n\n### Start-up\n\nold start\n\n{_block('record start')}\n\n"
           f"### Cost\n\nold cost\n\n{_block('record cost')}\n\n## Reproduce\n\nrun it\n")
    section = [I14_HEADING + "\n", "new i14 text\n", "### Start-up\n", "new start\n", "### Cost\n", "new cost\n"]
    out = splice_issue14(old, section)
    assert "old " not in out
    for text in ("intro kept", "a kept", "record a", "new i14 text", "new start", "record start", "new cost",
                 "record cost", "run it", I14_HEADING):
        assert out.count(text) == 1, text
    order = ["intro kept", "a kept", "record a", I14_HEADING, "new i14 text", "new start", "record start",
             "new cost", "record cost", "## Reproduce"]
    assert [out.index(t) for t in order] == sorted(out.index(t) for t in order)
    assert I14_OLD_HEADINGS[0] not in out
    with pytest.raises(ValueError):
        splice_issue14("# Page\n\n## A\n\nx\n", section)


def test_issue14_only_keeps_every_record_of_the_shipped_page():
    page = (ROOT / "docs" / "performance.md").read_text()
    out = splice_issue14(page, [I14_HEADING + "\n", "regenerated\n"])
    blocks = [ln for ln in page.splitlines() if ln.startswith("**")]
    for ln in blocks:
        assert ln in out, ln[:60]
    assert out.count(HAND_OPEN) == page.count(HAND_OPEN)

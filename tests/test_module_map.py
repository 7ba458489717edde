"""docs/design.md's module map names every module of the package.

The map ("Data flow and modules") is how a newcomer finds where an idea
lives; modules added without a line there (session 21 found 34) leave it
silently incomplete.  This test fails when a module is added, or renamed,
without its line.
"""
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_every_module_is_in_the_design_module_map():
    text = (ROOT / "docs" / "design.md").read_text(encoding="utf-8")
    start = text.index("## Data flow and modules")
    the_map = text[start:text.index("\n## ", start + 1)]
    missing = [str(p.relative_to(ROOT)) for p in sorted((ROOT / "bifilar").rglob("*.py"))
               if p.name not in ("__init__.py", "__main__.py") and p.name not in the_map]
    assert not missing, f"modules missing from docs/design.md's module map: {missing}"

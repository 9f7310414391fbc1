"""The docs' shape: the README is a front door (at most 12 KB), each reference page at most about 250
lines, dated history only under docs/journal/, and every page a reference page links exists."""
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
REFERENCE = sorted((ROOT / "docs").glob("*.md"))
DATED = re.compile(r"\bsession\s+20\d\d-\d\d-\d\d|\(this session\)")


def test_the_readme_is_at_most_12_kb():
    assert (ROOT / "README.md").stat().st_size <= 12_000


@pytest.mark.parametrize("page", REFERENCE, ids=lambda p: p.name)
def test_a_reference_page_is_short_and_undated(page):
    text = page.read_text()
    assert len(text.splitlines()) <= 250, f"{page.name}: move detail or history out (docs/journal/)"
    assert not DATED.findall(text), f"{page.name} has session notes: {DATED.findall(text)[:3]} (docs/journal/)"


@pytest.mark.parametrize("page", [ROOT / "README.md", *REFERENCE], ids=lambda p: p.name)
def test_the_pages_a_page_links_exist(page):
    for target in re.findall(r"\]\(([^)#:]+\.md)\)", page.read_text()):
        assert (page.parent / target).is_file(), f"{page.name} links {target}"

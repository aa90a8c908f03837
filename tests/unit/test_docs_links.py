"""Every relative link of the README and of the guide in docs/ leads somewhere: the file
exists, and its `#anchor` is a heading of that file (as GitHub names it) or an explicit
`<a id="...">`. A reader who follows a link never lands on nothing."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
LINK = re.compile(r"(?<!!)\[[^\]]*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")


def prose(text: str, keep_code: bool = False) -> str:
    """The text without fenced code blocks and inline code, where `[x](y)` is no link
    (`keep_code`: inline code stays, as text, as GitHub keeps it in a heading's anchor)."""
    text = re.sub(r"^(```|~~~).*?^\1", "", text, flags=re.M | re.S)
    return text if keep_code else re.sub(r"`[^`\n]*`", "", text)


def anchors(page: Path) -> set[str]:
    """GitHub's anchors of a page: each heading, lowercased, punctuation dropped, spaces
    as hyphens (`-1`, `-2` for repeats), and every explicit id."""
    text = page.read_text()
    found = set(re.findall(r"""\bid=["']([^"']+)["']""", text))
    seen: dict[str, int] = {}
    for heading in re.findall(r"^#{1,6}\s+(.+?)\s*#*\s*$", prose(text, keep_code=True),
                              flags=re.M):
        plain = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", heading)  # a link: its text
        slug = re.sub(r"[^\w\- ]", "", plain.lower()).replace(" ", "-")
        count = seen.get(slug, 0)
        seen[slug] = count + 1
        found.add(slug if count == 0 else f"{slug}-{count}")
    return found


def links() -> list[tuple[Path, str]]:
    out = []
    for page in PAGES:
        for target in LINK.findall(prose(page.read_text())):
            if not re.match(r"[a-z][a-z0-9+.-]*:", target):  # http:, mailto: ...
                out.append((page, target))
    return out


def test_the_guide_has_links_to_check():
    assert len(links()) >= 10  # the README's tour alone links every page of docs/


@pytest.mark.parametrize("page, target", links(),
                         ids=[f"{p.relative_to(ROOT)}->{t}" for p, t in links()])
def test_a_relative_link_resolves_to_a_file_and_its_anchor(page: Path, target: str):
    path, _, anchor = target.partition("#")
    goal = (page.parent / path).resolve() if path else page
    assert goal.exists(), f"{page.relative_to(ROOT)}: {target} leads to no file"
    assert ROOT in goal.parents or goal == ROOT, f"{page.relative_to(ROOT)}: {target} " \
        "leads out of the repository"
    if anchor:
        assert goal.suffix == ".md", f"{target}: an anchor in a file that is not a page"
        assert anchor in anchors(goal), \
            f"{page.relative_to(ROOT)}: {target}: no heading or id '{anchor}' in {goal.name}"

"""Every relative link in the documentation resolves: README.md, docs/, release/ and every Markdown file under
research/. A link ``[text](path)`` or ``![alt](path)`` must name an existing file or folder (http(s) and other
URLs are not followed); where it also names a heading of a Markdown file (``path.md#heading``, or ``#heading``
in the same file), that heading must exist, under GitHub's rule for heading anchors."""

from __future__ import annotations

import re
import unicodedata
from pathlib import Path
from urllib.parse import unquote

import pytest

ROOT = Path(__file__).resolve().parent.parent

#: ``[text](target)`` and ``![alt](target)``; the text may hold one level of brackets, the target a title
#: (``(path "title")``) or sit in ``<…>``.
LINK = re.compile(r"!?\[(?:[^\[\]]|\[[^\[\]]*\])*\]\(\s*<?([^()\s<>]+(?:\([^()\s]*\)[^()\s<>]*)*)>?(?:\s+\"[^\"]*\")?\s*\)")
FENCE = re.compile(r"^\s*(```|~~~)")
HEADING = re.compile(r"^#{1,6}\s+(.*?)\s*#*\s*$")


def _documents() -> list[Path]:
    found = [ROOT / "README.md", *(ROOT / "docs").rglob("*.md"), *(ROOT / "release").rglob("*.md"),
             *(ROOT / "research").rglob("*.md")]
    return sorted(path for path in found if path.is_file())


def _prose(text: str):
    """(line number, line) of each line outside fenced code blocks."""
    fenced = False
    for number, line in enumerate(text.splitlines(), 1):
        if FENCE.match(line):
            fenced = not fenced
        elif not fenced:
            yield number, line


def _links(text: str) -> list[tuple[int, str]]:
    """(line number, target) of each Markdown link outside code (fenced blocks and inline spans)."""
    return [(number, match.group(1)) for number, line in _prose(text)
            for match in LINK.finditer(re.sub(r"`[^`]*`", "", line))]


def _slug(heading: str) -> str:
    """GitHub's anchor of a heading: its text lower-cased, links reduced to their text, every character but
    letters, marks, digits, ``_``, ``-`` and spaces dropped, spaces made hyphens."""
    text = re.sub(r"!?\[([^\]]*)\]\([^)]*\)", r"\1", heading).lower()
    kept = "".join(ch for ch in text if ch in " -_" or unicodedata.category(ch)[0] in "LMN")
    return kept.replace(" ", "-")


def anchors(path: Path) -> set[str]:
    """The anchors of a Markdown file's headings (a repeated one gets ``-1``, ``-2``, … as on GitHub)."""
    seen: dict[str, int] = {}
    found = set()
    for _, line in _prose(path.read_text(encoding="utf-8")):
        if match := HEADING.match(line):
            slug = _slug(match.group(1))
            found.add(f"{slug}-{seen[slug]}" if slug in seen else slug)
            seen[slug] = seen.get(slug, 0) + 1
    return found


def _is_relative(target: str) -> bool:
    return not re.match(r"^[a-zA-Z][a-zA-Z0-9+.-]*:", target)


def broken_links(path: Path, root: Path = ROOT) -> list[str]:
    """The relative links of one Markdown file that resolve to no file or folder, or to no heading of a Markdown
    file, as ``file:line: target`` (a target starting with ``/`` is read from ``root``)."""
    broken = []
    for number, target in _links(path.read_text(encoding="utf-8")):
        if not _is_relative(target):
            continue
        file_part, _, anchor = target.partition("#")
        file_part = unquote(file_part.split("?", 1)[0])
        if not file_part:
            resolved = path
        elif file_part.startswith("/"):
            resolved = root / file_part.lstrip("/")
        else:
            resolved = path.parent / file_part
        if not resolved.exists():
            broken.append(f"{path.relative_to(root)}:{number}: {target}")
        elif anchor and resolved.suffix == ".md" and unquote(anchor).lower() not in anchors(resolved):
            broken.append(f"{path.relative_to(root)}:{number}: {target} (no such heading)")
    return broken


def test_the_link_finder_sees_links_and_skips_code_and_urls():
    text = ("[a](there.md) ![b](missing.png) [c](https://example.org/x.md) [d](#anchor)\n"
            "`[e](in-code.md)` [f](there.md#part) [g [h]](gone/)\n```\n[i](fenced.md)\n```\n")
    assert [target for _, target in _links(text)] == [
        "there.md", "missing.png", "https://example.org/x.md", "#anchor", "there.md#part", "gone/"]


def test_headings_become_github_anchors(tmp_path):
    page = tmp_path / "page.md"
    page.write_text("# Title\n## The `features` bank (`frenbrdf synth --mix features`)\n"
                    "## Test-time refinement (`python/frenbrdf/models/reconstruct.py`)\n"
                    "## Does any variant beat η = 0?\n## Title\n```\n# not a heading\n```\n")
    assert anchors(page) == {"title", "the-features-bank-frenbrdf-synth---mix-features",
                             "test-time-refinement-pythonfrenbrdfmodelsreconstructpy",
                             "does-any-variant-beat-η--0", "title-1"}


def test_a_missing_file_folder_or_heading_is_reported(tmp_path):
    (tmp_path / "there.md").write_text("# Part\n")
    (tmp_path / "folder").mkdir()
    page = tmp_path / "page.md"
    page.write_text("[a](there.md#part) [b](folder/) [c](#top)\n# Top\n"
                    "[d](missing.png) [e](gone/) [f](there.md#whole) [g](#bottom) [h](http://example.org/x)\n")
    assert broken_links(page, root=tmp_path) == [
        "page.md:3: missing.png", "page.md:3: gone/", "page.md:3: there.md#whole (no such heading)",
        "page.md:3: #bottom (no such heading)"]


@pytest.mark.parametrize("path", _documents(), ids=lambda path: str(path.relative_to(ROOT)))
def test_every_relative_link_resolves(path):
    broken = broken_links(path)
    assert not broken, "relative links to no file, folder or heading:\n" + "\n".join(broken)

"""The documentation's relative links resolve: every Markdown link or image in README.md and docs/**/*.md that is
not a URL points to a file or folder of the repository (code spans and fenced code are not links)."""

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
FENCE = re.compile(r"^(```|~~~).*?^\1[^\n]*$", re.M | re.S)
CODE_SPAN = re.compile(r"(`+)(?:(?!\1).)+?\1", re.S)
INLINE = re.compile(r"!?\[[^\]\n]*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")
REFERENCE = re.compile(r"^\s{0,3}\[[^\]\n]+\]:\s*<?(\S+?)>?(?:\s+\"[^\"]*\")?\s*$", re.M)
SCHEME = re.compile(r"^[a-zA-Z][a-zA-Z0-9+.-]*:")


def docs() -> list[Path]:
    return [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]


def links(text: str) -> list[str]:
    """Link targets of Markdown text, outside code; URLs and in-page anchors left out, anchors cut off."""
    prose = CODE_SPAN.sub("", FENCE.sub("", text))
    targets = INLINE.findall(prose) + REFERENCE.findall(prose)
    return [t.split("#", 1)[0] for t in targets if not SCHEME.match(t) and not t.startswith("#")]


def broken(path: Path) -> list[str]:
    return [t for t in links(path.read_text(encoding="utf-8")) if t and not (path.parent / t).exists()]


def test_the_link_finder_sees_links_and_skips_code() -> None:
    text = ("[a](docs/x.md) ![img](pic.png \"title\") [web](https://example.org) [here](#part) `[no](code.md)`\n"
            "```\n[no](fenced.md)\n```\n[ref]: other.md#sec\n[b](y.md#anchor)\n")
    assert links(text) == ["docs/x.md", "pic.png", "y.md", "other.md"]


def test_a_missing_target_is_reported(tmp_path: Path) -> None:
    (tmp_path / "there.md").write_text("x")
    page = tmp_path / "page.md"
    page.write_text("[ok](there.md) [gone](missing.md) [folder](.)")
    assert broken(page) == ["missing.md"]


@pytest.mark.parametrize("path", docs(), ids=lambda p: str(p.relative_to(ROOT)))
def test_relative_links_resolve(path: Path) -> None:
    assert broken(path) == [], f"{path.relative_to(ROOT)} links to missing files"

"""The documentation's references: the model's specification is docs/model.md, and every link to
a section of a page names a heading that page has."""
from __future__ import annotations

import re
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
MODEL = "docs/model.md"
OLD_NAME = "MODEL" + ".md"  # spelled apart so that this file does not cite it


def tracked_text_files() -> dict[str, str]:
    """Path -> text of every file git tracks that reads as UTF-8."""
    try:
        listed = subprocess.run(["git", "ls-files", "-z"], cwd=REPO, capture_output=True,
                                check=True, text=True).stdout
    except (OSError, subprocess.CalledProcessError):
        pytest.skip("not a git checkout")
    texts = {}
    for name in filter(None, listed.split("\0")):
        try:
            texts[name] = (REPO / name).read_text(encoding="utf-8")
        except (UnicodeDecodeError, FileNotFoundError, IsADirectoryError):
            continue
    return texts


def anchor(heading: str) -> str:
    """GitHub's anchor of a markdown heading: lower case, punctuation other than '-' and '_'
    dropped, spaces as '-'."""
    return re.sub(r"[^\w\- ]", "", heading.strip().lower()).replace(" ", "-")


def anchors(markdown: str) -> set[str]:
    """The anchors of every heading of a markdown page, outside fenced code."""
    text = re.sub(r"^```.*?^```", "", markdown, flags=re.S | re.M)
    return {anchor(line.lstrip("#")) for line in text.splitlines() if re.match(r"#{1,6} ", line)}


def test_only_docs_model_names_the_page_it_was_copied_from():
    citing = [name for name, text in tracked_text_files().items()
              if OLD_NAME in text and name != MODEL]
    assert citing == []


def test_docs_model_says_where_it_came_from():
    text = (REPO / MODEL).read_text(encoding="utf-8")
    assert "Where it came from" in text and f"`{OLD_NAME}`" in text


def test_every_link_to_a_section_of_docs_model_names_one_of_its_headings():
    headings = anchors((REPO / MODEL).read_text(encoding="utf-8"))
    assert {"contacts", "history", "stability", "units", "targets",
            "decisions-this-project-made-where-modelmd-is-silent"} <= headings
    cited = {(name, each) for name, text in tracked_text_files().items()
             for each in re.findall(r"model\.md#([\w-]+)", text)}
    assert len(cited) > 20  # the pages and the sources cite its sections
    assert sorted((name, each) for name, each in cited if each not in headings) == []


def test_every_link_to_a_section_of_a_page_in_docs_names_one_of_its_headings():
    """Markdown links [text](page.md#anchor) in README.md and docs/, to pages in docs/."""
    pages = {path.name: anchors(path.read_text(encoding="utf-8"))
             for path in (REPO / "docs").glob("*.md")}
    broken = []
    for path in [REPO / "README.md", *(REPO / "docs").glob("*.md")]:
        for page, each in re.findall(r"\]\((?:docs/)?(\w+\.md)#([^)\s]+)\)",
                                     path.read_text(encoding="utf-8")):
            if page in pages and each not in pages[page]:
                broken.append((path.name, page, each))
    assert broken == []

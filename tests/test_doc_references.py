"""Every README section, docs page and heading the library names (in its code, comments and
``--help``) exists: the front door never points the wrong way."""

from __future__ import annotations

import argparse
import re
from pathlib import Path

import pytest

from sim.cli.parser import build_parser

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("wbc", "tasks", "actions", "sim", "benchmarks")
#: ``README's "Section"``, ``README "Section"``.
README_SECTION = re.compile(r"README(?:'s)? \"(?P<title>[^\"]+)\"")
#: ``docs/page.md``, ``docs/page.md#anchor``, ``docs/page.md, "Heading"``,
#: ``README.md#anchor``.
DOCS_PAGE = re.compile(r"(?P<page>docs/[\w.-]+\.md|README\.md)(?:#(?P<anchor>[\w-]+))?"
                       r"(?:,? \(?\"(?P<title>[^\"]+)\")?")


def sections(page: Path) -> list[str]:
    """The titles a reader can look for on ``page``: its headings and the bold leads that
    open its paragraphs (``**The simulated sensors** ...``), lower case."""
    titles = []
    for line in page.read_text().splitlines():
        if line.startswith("#"):
            titles.append(line.lstrip("#").strip().lower())
        elif line.startswith("**"):
            titles.append(line[2:].split("**", 1)[0].rstrip(".").lower())
    return titles


def anchors(page: Path) -> set[str]:
    """GitHub's anchors for a page's headings."""
    return {re.sub(r"[^\w\- ]", "", title).replace(" ", "-")
            for title in sections(page) if title}


def flat(text: str) -> str:
    """``text`` as one line: comment markers at line starts dropped, spaces collapsed (a
    reference may wrap)."""
    return re.sub(r"\s+", " ", re.sub(r"\n\s*#:?", " ", text))


def broken_references(where: str, text: str) -> tuple[list[str], int]:
    """The references in ``text`` to sections or pages that do not exist, and how many
    references there were."""
    text = flat(text)
    broken, count = [], 0
    readme = ROOT / "README.md"
    for match in README_SECTION.finditer(text):
        count += 1
        title = match["title"].lower()
        if not any(section.startswith(title) for section in sections(readme)):
            broken.append(f"{where}: {match[0]} (README.md has no such section)")
    for match in DOCS_PAGE.finditer(text):
        count += 1
        page = ROOT / match["page"]
        if not page.is_file():
            broken.append(f"{where}: {match['page']} (no such page)")
            continue
        if match["anchor"] and match["anchor"] not in anchors(page):
            broken.append(f"{where}: {match[0]} (no heading #{match['anchor']})")
        title = (match["title"] or "").lower()
        if title and not any(section.startswith(title) for section in sections(page)):
            broken.append(f"{where}: {match[0]} (no section {match['title']!r} there)")
    return broken, count


def help_texts() -> dict[str, str]:
    """``go2-wbc --help`` and every command's."""
    parser = build_parser()
    texts = {"go2-wbc --help": parser.format_help()}
    for action in parser._actions:  # argparse keeps its subcommands there
        if isinstance(action, argparse._SubParsersAction):
            for name, command in action.choices.items():
                texts[f"go2-wbc {name} --help"] = command.format_help()
    return texts


def test_the_library_names_only_sections_that_exist() -> None:
    broken, count = [], 0
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*.py")):
            found, n = broken_references(str(path.relative_to(ROOT)), path.read_text())
            broken += found
            count += n
    assert count >= 5, "the library names docs pages in a few places; the reader found none"
    assert not broken, "\n".join(broken)


def test_help_names_only_sections_that_exist() -> None:
    texts = help_texts()
    assert len(texts) >= 10  # every command's --help was read
    broken = [line for where, text in texts.items() for line in broken_references(where, text)[0]]
    assert not broken, "\n".join(broken)


@pytest.mark.parametrize(("text", "problem"), [
    ('the README\'s "State estimation" section', "README.md has no such section"),
    ("see docs/nowhere.md", "no such page"),
    ("docs/dds.md#the-fallback", "no heading #the-fallback"),
    ('docs/state-estimation.md, "The sensors" table', None),
    ('docs/dds.md, "When the state\n    #: stops"', None),
    ('docs/dds.md, "Where it lives"', "no section 'Where it lives' there"),
])
def test_the_reader_finds_what_is_broken(text: str, problem: str | None) -> None:
    broken, count = broken_references("here", text)
    assert count == 1
    assert [problem in line for line in broken] == ([True] if problem else [])

"""The README's pictures are this release's: each is in docs/pictures.json as it is on disk
(``scripts/docs_media.py`` makes them and writes it), and the numbers the pages quote beside
them are those of the run that made them."""

from __future__ import annotations

import hashlib
import json
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
#: The pages that show pictures: the README and the pages it links in docs/.
PAGES = [ROOT / "README.md", *sorted(DOCS.glob("*.md"))]
MANIFEST_PATH = DOCS / "pictures.json"
#: A picture shown on a page: ``![alt](path)``.
IMAGE = re.compile(r"!\[[^\]]*\]\((?P<path>[^)\s]+\.(?:png|gif|jpg|svg))\)")
#: How a page is to write the plot's run, in the text under it (before the next heading);
#: a space may be a line break.
PLOT_QUOTE = re.compile(
    r"control tick (?P<median>[\d,]+) µs median and (?P<max>[\d,.]+) (?P<unit>µs|ms) at "
    r"most, the raised foot (?P<rms>[\d.]+) mm RMS".replace(" ", r"\s+"))
#: The row of the "Every backend" table that the QP timing picture's first box is.
QP_ROW = "| **default (DAQP, reduced QP)**"
REMAKE = "remake the pictures with scripts/docs_media.py, or update the page"


def shown() -> dict[str, list[tuple[Path, int]]]:
    """Each picture in docs/ that a page shows: the pages and where in them."""
    pictures: dict[str, list[tuple[Path, int]]] = {}
    for page in PAGES:
        text = page.read_text(encoding="utf-8")
        for match in IMAGE.finditer(text):
            path = (page.parent / match["path"]).resolve()
            assert path.parent == DOCS, f"{page.name} shows {match['path']}, outside docs/"
            pictures.setdefault(path.name, []).append((page, match.start()))
    return pictures


def page_showing(name: str) -> tuple[str, int, str]:
    """The text of the page that shows picture ``name``, where, and the page's name."""
    (page, at), *_ = shown()[name]
    return page.read_text(encoding="utf-8"), at, page.name


@pytest.fixture(scope="module")
def manifest() -> dict:
    return json.loads(MANIFEST_PATH.read_text())


def agrees(text: str, value: float) -> bool:
    """Whether a number as the README writes it (``31``, ``1.89``, ``1,133``) is ``value``
    rounded to as many digits."""
    digits = text.replace(",", "")
    decimals = len(digits.partition(".")[2])
    return abs(float(digits) - value) <= 0.5 * 10.0 ** -decimals + 1e-9


@pytest.mark.parametrize(("text", "value", "expected"), [
    ("31", 31.4, True), ("31", 31.6, False), ("1.89", 1.894, True), ("1.89", 1.9, False),
    ("1,133", 1133.2, True), ("0.3", 0.25, True), ("0.3", 0.24, False),
])
def test_a_quoted_number_agrees_with_the_value_rounded_to_its_digits(text, value, expected):
    assert agrees(text, value) is expected


def test_every_picture_the_pages_show_is_in_the_manifest_as_it_is_on_disk(manifest):
    pictures = shown()
    assert "high_five.png" in pictures and "high_five_plot.png" in pictures
    assert sorted(manifest) == sorted(pictures), (
        f"docs/pictures.json and the pages' pictures differ: {REMAKE}")
    for name, entry in manifest.items():
        data = (DOCS / name).read_bytes()
        assert hashlib.sha256(data).hexdigest() == entry["sha256"], (
            f"docs/{name} is not the picture docs/pictures.json records: {REMAKE}")
        assert entry["made_by"] and entry["commit"], name


def test_the_plot_s_caption_quotes_the_run_that_drew_it(manifest):
    numbers = manifest["high_five_plot.png"]["numbers"]
    text, at, page = page_showing("high_five_plot.png")
    end = text.find("\n#", at)
    quotes = list(PLOT_QUOTE.finditer(text[at:end if end >= 0 else None]))
    assert len(quotes) == 1, (
        f"the text under docs/high_five_plot.png in {page} should say, once: 'control tick "
        "N µs median and M µs at most, the raised foot R mm RMS' (scripts/docs_media.py "
        "prints it)")
    quote = quotes[0]
    scale = 1e-3 if quote["unit"] == "ms" else 1.0
    for key, field in (("median", "tick_median_us"), ("max", "tick_max_us"),
                       ("rms", "raised_foot_rms_mm")):
        value = numbers[field] * (scale if key == "max" else 1.0)
        assert agrees(quote[key], value), (f"{page} says {quote[0]!r}; the plot's run had "
                                           f"{field} {numbers[field]}: {REMAKE}")


def test_the_qp_table_s_default_row_is_the_run_the_qp_picture_shows(manifest):
    numbers = manifest["qp_timing.png"]["numbers"]
    assert numbers["mode"] == "full"
    text, _, page = page_showing("qp_timing.png")
    lines = text.splitlines()
    (row,) = [i for i, line in enumerate(lines) if line.startswith(QP_ROW)]
    header = next(lines[i] for i in range(row, -1, -1) if lines[i].startswith("| backend |"))
    columns = [cell.strip() for cell in header.strip("|").split("|")]
    cells = [cell.strip() for cell in lines[row].strip("|").split("|")]
    for column in ("median", "p90", "p99"):
        value = numbers[f"{column}_us"]
        assert agrees(cells[columns.index(column)], value), (
            f"{page}'s table says {column} {cells[columns.index(column)]} µs; the qp "
            f"picture's run had {value}: {REMAKE}")


def test_the_sweep_s_counts_are_the_run_the_sweep_picture_shows(manifest):
    numbers = manifest["sweep_plant_pushes.png"]["numbers"]
    text, at, page = page_showing("sweep_plant_pushes.png")
    succeeded, episodes = re.findall(r"succeeded (\d+)/(\d+)", text[:at])[-1]
    assert (int(succeeded), int(episodes)) == (numbers["succeeded"], numbers["episodes"]), (
        f"{page} says succeeded {succeeded}/{episodes} above the sweep's picture; its run "
        f"had {numbers['succeeded']}/{numbers['episodes']}: {REMAKE}")

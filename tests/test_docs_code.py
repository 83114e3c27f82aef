"""The README and the docs pages say what is true: every Python block runs as written, and
every link between them points at a file and a heading that exist."""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import pytest

from sim.cli import main

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
_BLOCK = re.compile(r"^```python\n(.*?)^```", re.DOTALL | re.MULTILINE)
_BASH = re.compile(r"^```bash\n(.*?)^```", re.DOTALL | re.MULTILINE)
_LINK = re.compile(r"\]\(([^)\s]+)\)")


def python_blocks(page: Path) -> list[str]:
    return _BLOCK.findall(page.read_text())


def heading_anchors(page: Path) -> set[str]:
    """GitHub's anchors for a page's headings: lower case, punctuation dropped, spaces to
    hyphens (code blocks' comment lines are not headings)."""
    text = re.sub(r"^```.*?^```", "", page.read_text(), flags=re.DOTALL | re.MULTILINE)
    anchors = set()
    for title in re.findall(r"^#+ (.+)$", text, flags=re.MULTILINE):
        slug = re.sub(r"[^\w\- ]", "", title.strip().lower()).replace(" ", "-")
        anchors.add(slug)
    return anchors


def test_the_pages_have_python_blocks():
    # The search above would pass vacuously if the fence syntax changed.
    assert len(python_blocks(ROOT / "README.md")) >= 2
    assert sum(len(python_blocks(page)) for page in PAGES) >= 10


def readme_commands() -> list[str]:
    """The ``go2-wbc`` lines of the README's shell blocks, comments dropped."""
    lines = [line.split("  #")[0].strip()
             for block in _BASH.findall((ROOT / "README.md").read_text())
             for line in block.splitlines()]
    return [line for line in lines if line.startswith("go2-wbc ")]


@pytest.mark.parametrize("page", [page for page in PAGES if python_blocks(page)],
                         ids=lambda page: page.name)
def test_every_python_block_runs_as_written(page, capsys, monkeypatch):
    """A page's blocks run in order in one namespace, as a reader pastes them one after
    another into one interpreter."""
    blocks = python_blocks(page)
    monkeypatch.chdir(ROOT)
    namespace: dict = {"__name__": "__docs__"}
    for k, source in enumerate(blocks):
        code = compile(source, f"{page.name}, Python block {k + 1}", "exec")
        exec(code, namespace)  # the documentation's own code
    out = capsys.readouterr().out
    if page.name == "README.md":
        assert "SUCCEEDED high five done: foot raised to 0.400 m" in out
        assert "OK 6.3" in out
    if page.name == "state-estimation.md":
        assert "OK 0.334" in out


def test_the_readme_has_its_tour_of_commands():
    commands = readme_commands()
    assert len(commands) >= 8
    assert all("  " not in command for command in commands), commands


# The video line (~18 s: rendering every frame) is in the slow stage (`make test-slow`); the
# quick stage records a video in tests/test_cli.py.
@pytest.mark.parametrize("command", [
    pytest.param(command, marks=pytest.mark.slow) if "--video" in command else command
    for command in readme_commands()])
def test_every_readme_command_runs_as_written(command, tmp_path, monkeypatch, capsys):
    """Each ``go2-wbc`` line of the README exits 0 (its goal succeeded), run from a
    scratch folder so that the files it writes land there, with no display (the viewer's
    line runs headless, as on CI)."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    argv = shlex.split(command)[1:]
    code = main(argv)
    out = capsys.readouterr()
    assert code == 0, f"{command}: exit {code}\n{out.out[-2000:]}\n{out.err[-2000:]}"
    for path in (arg for arg in argv if arg.endswith((".png", ".mp4", ".json", ".npz"))):
        assert (tmp_path / path).stat().st_size > 0, path


def test_every_relative_link_points_at_a_file_and_heading_that_exist():
    broken = []
    for page in PAGES:
        for target in _LINK.findall(page.read_text()):
            if re.match(r"[a-z]+:", target):
                continue  # https://, mailto:
            path, _, anchor = target.partition("#")
            file = (page.parent / path).resolve() if path else page
            if not file.exists():
                broken.append(f"{page.name}: {target} (no such file)")
            elif anchor and anchor not in heading_anchors(file):
                broken.append(f"{page.name}: {target} (no heading #{anchor} in {file.name})")
    assert not broken, "\n".join(broken)

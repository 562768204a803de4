"""The manual in docs/: the API page covers every public name, the README's links lead somewhere, and the Sphinx
build (when the docs extra is installed, as in `.ci/run`) renders the API reference instead of printing it."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

import warpsim

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"


def test_the_api_page_documents_every_public_name_through_warpsim():
    text = (DOCS / "api.md").read_text(encoding="utf-8")
    documented = set(re.findall(r"^\.\. auto(?:class|function|data):: warpsim\.(\w+)$", text, re.M))
    public = set(warpsim.__all__) - {"__version__"}
    assert documented == public, f"missing: {sorted(public - documented)}, not public: {sorted(documented - public)}"
    # MyST hands autodoc's reStructuredText to the Markdown parser unless the directive sits in an eval-rst block
    assert not re.search(r"^```\{auto", text, re.M), "autodoc directives must be written inside ```{eval-rst} blocks"


def test_the_api_pages_first_example_runs_as_written(capsys):
    """The first Python block of docs/api.md (a flag built, stepped and measured without a scene), run as written:
    it flies, and its stretch is the woven cloth's shear (its diagonals), not a blow-up."""
    text = (DOCS / "api.md").read_text(encoding="utf-8")
    block = re.search(r"```python\n(.*?)```", text, re.S).group(1)
    exec(compile(block, "docs/api.md", "exec"), {})
    stretch = float(capsys.readouterr().out.split()[-1])
    assert 0.005 < stretch < 0.2, stretch


def test_the_readmes_links_and_pictures_exist():
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    targets = re.findall(r"\]\(((?!https?:|#)[^)#\s]+)(?:#[^)]*)?\)", text)
    assert len(targets) >= 12, targets
    missing = [t for t in targets if not (ROOT / t).exists()]
    assert not missing, missing


def test_the_readme_stays_short():
    lines = (ROOT / "README.md").read_text(encoding="utf-8").count("\n")
    assert lines <= 250, f"README.md has {lines} lines; the manual's prose belongs in docs/"


@pytest.mark.slow
def test_the_manual_builds_without_warnings_and_renders_the_api(tmp_path):
    pytest.importorskip("sphinx")
    pytest.importorskip("myst_parser")
    pytest.importorskip("pydata_sphinx_theme")
    out = tmp_path / "html"
    done = subprocess.run(
        [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html", str(DOCS), str(out)],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    api = (out / "api.html").read_text(encoding="utf-8")
    # rendered signatures, not the directive's text
    assert 'id="warpsim.Simulation"' in api and 'id="warpsim.SolverConfig"' in api
    assert ".. autoclass::" not in api and ".. py:class::" not in api


def _python_blocks() -> dict[str, list[str]]:
    """Every ```python block of the README and the manual, by file."""
    pages = [ROOT / "README.md", *sorted(DOCS.glob("*.md"))]
    return {p.name: re.findall(r"```python\n(.*?)```", p.read_text(encoding="utf-8"), re.S) for p in pages}


def test_the_docs_import_only_from_warpsim_itself():
    """The README's and the manual's examples use the public names (`import warpsim`, `from warpsim import ...`),
    never a module behind them: those may move (docs/architecture.md), the names stay."""
    blocks = _python_blocks()
    assert sum(len(b) for b in blocks.values()) >= 3
    inner = [
        f"{name}: {line.strip()}"
        for name, found in blocks.items()
        for block in found
        for line in block.splitlines()
        if re.match(r"\s*(from|import)\s+warpsim\.", line)
    ]
    assert not inner, inner


def test_the_readmes_example_flies_the_kite_and_reads_its_figures_as_the_command_prints_them(capsys):
    """The README's Python block, run as written: the kite, its anchor walked 10 m downwind, flies 20 s more and
    its line's angle over the last 10 s (`Simulation.fly`'s rows, the columns of `--table`) is a kite's (40-70°,
    the validation's band); the figures of `sim.fly` are the lines `warpsim run` prints for the same flight."""
    (block,) = _python_blocks()["README.md"]
    exec(compile(block, "README.md", "exec"), {})
    angle = float(capsys.readouterr().out.split()[-1])
    assert 40.0 < angle < 70.0, angle

    from warpsim.cli import main

    assert main(["run", "kite", "--seconds", "4"]) == 0
    printed = capsys.readouterr().out.splitlines()
    flight = warpsim.Simulation(warpsim.defaults("kite")).fly(4.0)
    figures = flight.figures.lines()
    assert figures and all(line in printed for line in figures), (figures, printed)
    assert flight.rows()[0]["line_angle_mean"] > 0.0 and flight.summary.simulated_time == 4.0

"""The README's tour runs as written, and prints the figures the README quotes.

The tour is the first ``bash`` block of the README's "## A tour" section; the figures are the ``text`` block that
follows it. The block runs in a fresh folder that holds only the links a clone's folder has for it (``.venv`` to
the virtual environment running these tests, ``scenes`` to the repository's), as one ``bash -e`` script, so any
command that fails fails the tour.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"


def tour_blocks(text: str) -> tuple[str, list[str]]:
    """(the tour's bash script, the figure lines the README shows after it) from the README's text."""
    section = re.search(r"^## A tour\n(.*?)(?=^## )", text, re.S | re.M)
    assert section, "README.md has no '## A tour' section"
    blocks = re.findall(r"^```(\w*)\n(.*?)^```", section.group(1), re.S | re.M)
    scripts = [body for lang, body in blocks if lang == "bash"]
    figures = [body for lang, body in blocks if lang == "text"]
    assert scripts and figures, "the tour section needs a bash block (the tour) and a text block (its figures)"
    return scripts[0], [line for line in figures[0].splitlines() if line.strip()]


def test_the_tour_is_one_screen_and_writes_distinct_outputs():
    script, figures = tour_blocks(README.read_text(encoding="utf-8"))
    commands = [line for line in script.splitlines() if line.strip() and not line.startswith("#")]
    assert len(commands) <= 20, "the tour should fit on one screen"
    assert commands[0].startswith("source .venv/bin/activate"), "the tour starts from the set-up's .venv"
    outs = re.findall(r"--out (\S+)", script)
    assert len(outs) == len(set(outs)), f"two sweeps of the tour write the same table: {outs}"
    assert figures, "the README shows what the tour prints"


@pytest.mark.slow
def test_the_readme_tour_runs_as_written(tmp_path):
    if sys.prefix == sys.base_prefix:
        pytest.skip("the tour sources .venv/bin/activate: run the tests from a virtual environment")
    venv = Path(sys.prefix)
    if not (venv / "bin" / "activate").exists() or not (venv / "bin" / "warpsim").exists():
        pytest.skip(f"{venv} has no bin/activate or bin/warpsim (pip install -e . into it)")
    script, figures = tour_blocks(README.read_text(encoding="utf-8"))
    (tmp_path / ".venv").symlink_to(venv, target_is_directory=True)
    (tmp_path / "scenes").symlink_to(ROOT / "scenes", target_is_directory=True)
    env = {k: v for k, v in os.environ.items() if not k.startswith("WARPSIM_")}
    done = subprocess.run(
        ["bash", "-e", "-o", "pipefail", "-c", script],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )
    output = done.stdout + done.stderr
    assert done.returncode == 0, f"the tour failed (exit {done.returncode}):\n{output[-4000:]}"

    # what the tour says it writes, readable
    for name in ("kite.h5", "kite.png", "tour.parquet", "tour.png"):
        assert (tmp_path / name).stat().st_size > 0, name
    from PIL import Image

    for name in ("kite.png", "tour.png"):
        with Image.open(tmp_path / name) as picture:
            assert picture.format == "PNG" and min(picture.size) >= 200, (name, picture.size)
    import pandas as pd

    table = pd.read_parquet(tmp_path / "tour.parquet")
    assert len(table) == 9 and not table["blew_up"].any(), table
    assert "exit code 3" in output, "the Euler flag at dt 0.01 should blow up with exit code 3"

    # every figure line the README quotes, as this run printed it
    printed = {line.strip() for line in output.splitlines()}
    missing = [line for line in figures if line.strip() not in printed]
    candidates = [line for line in output.splitlines() if re.match(r"\s*\w+: altitude ", line)]
    assert not missing, (
        "the README's tour figures differ from what the tour prints; README says:\n"
        + "\n".join(missing)
        + "\nthe tour printed:\n"
        + "\n".join(candidates)
    )

"""Validation suite: ``python -m benchmarks.validation`` compares warpsim with analytic solutions and published
measurements, measures how the stick stretch converges with iterations and dt, and runs a simulated hour of
the gusty kite. See :mod:`benchmarks.validation.cases` and the README's Validation section."""


def picture_command(prog: str, description: str, default: str, argv: list[str] | None = None):
    """A picture script's command line: its one optional ``OUT.png`` argument (default ``default``) parsed from
    ``argv``, and ``matplotlib.pyplot`` set to draw into files (Agg). Returns ``(out, plt)``."""
    import argparse

    parser = argparse.ArgumentParser(prog=prog, description=description)
    parser.add_argument("out", nargs="?", default=default, help="the picture (PNG)")
    out = parser.parse_args(argv).out
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return out, plt


def save_picture(fig, title: str, out: str) -> int:
    """Title ``fig``, lay it out, write it to ``out`` (PNG, 80 dpi) and say so; returns the exit code 0."""
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(out, dpi=80)
    print(f"wrote {out}")
    return 0

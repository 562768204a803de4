"""How to install one of warpsim's optional extras, said the way that works for this installation: from a
source checkout (the package sits beside the project's ``pyproject.toml``) ``pip install -e '.[EXTRA]'`` in its
folder, else ``pip install 'warpsim[EXTRA]'``. Any layer may use it (no warpsim imports)."""

from __future__ import annotations

from pathlib import Path

_ROOT = Path(__file__).resolve().parent.parent
_CHECKOUT = (_ROOT / "pyproject.toml").is_file()


def install_hint(extra: str) -> str:
    """The pip command that adds the ``extra`` (``viewer``, ``render``, ``sweep``, ...) to this installation."""
    if _CHECKOUT:
        return f"pip install -e '.[{extra}]' (in {_ROOT})"
    return f"pip install 'warpsim[{extra}]'"

"""The ``warpsim`` command line: :mod:`.main` (the parser and the mapping of errors to exit codes), :mod:`.common`
(the options and checks every command shares) and one module per command (:mod:`.run`, :mod:`.view`, ...)."""

from .common import EXIT_BLOWUP, EXIT_INTERRUPTED, EXIT_OUTPUT, EXIT_USAGE, MAX_LINE
from .main import build_parser, main

__all__ = ["EXIT_BLOWUP", "EXIT_INTERRUPTED", "EXIT_OUTPUT", "EXIT_USAGE", "MAX_LINE", "build_parser", "main"]

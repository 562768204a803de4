"""The ``warpsim`` command line: one module per command, the shared options and the exit codes."""

from .main import EXIT_BLOWUP, EXIT_INTERRUPTED, EXIT_OUTPUT, EXIT_USAGE, MAX_LINE, build_parser, main

__all__ = ["EXIT_BLOWUP", "EXIT_INTERRUPTED", "EXIT_OUTPUT", "EXIT_USAGE", "MAX_LINE", "build_parser", "main"]

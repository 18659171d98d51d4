"""Command line: ``igl-heatseg segment MESH -o DIR`` and the other subcommands.

One module per subcommand, each with ``register(subparsers)``; the parser it adds sets
``func`` (``args -> int``). Bad input (:class:`~igl_heatseg.MeshError`, or a bad parameter
value) is one line on stderr and exit code 2, never a traceback. The library never imports
this package.
"""

from __future__ import annotations

import argparse
import logging
import sys

from ..errors import MeshError
from ..version import __version__
from . import batch, cad, compare, evaluate, run, segment, viz
from .common import PROGRESS_MIN_FACES, Progress

__all__ = ["main", "build_parser", "Progress", "PROGRESS_MIN_FACES"]

log = logging.getLogger("igl_heatseg")

#: Subcommand modules, in the order ``--help`` lists them.
_COMMANDS = (segment, run, cad, batch, viz, evaluate, compare)


def build_parser() -> argparse.ArgumentParser:
    """The ``igl-heatseg`` argument parser with every subcommand registered."""
    parser = argparse.ArgumentParser(
        prog="igl-heatseg",
        description="Heat-based segmentation of triangle meshes into parameterizable patches "
        "(Mejia et al. 2018), built on libigl.",
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    parser.add_argument("-v", "--verbose", action="store_true", help="log progress details")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for module in _COMMANDS:
        module.register(sub)
    return parser
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the command line.

    Parameters
    ----------
    argv : list of str, optional
        Arguments without the program name (default ``sys.argv[1:]``).

    Returns
    -------
    int
        0 on success, 2 on bad input (one line on stderr), 1 on an unexpected failure.
    """
    parser = build_parser()
    args = parser.parse_args(argv)
    logging.basicConfig(
        level=logging.INFO if args.verbose else logging.WARNING,
        format="%(name)s: %(message)s",
    )
    if not getattr(args, "func", None):
        parser.print_help(sys.stderr)
        return 2
    held = _HeldWarnings()
    package = logging.getLogger("igl_heatseg")
    if not args.verbose:
        package.addHandler(held)
        package.propagate = False
    try:
        code = int(args.func(args) or 0)
        held.flush_to(sys.stderr)
        return code
    except (MeshError, ValueError, OSError) as exc:
        print(f"igl-heatseg: error: {exc}{held.summary()}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("igl-heatseg: interrupted", file=sys.stderr)
        return 130
    finally:
        package.removeHandler(held)
        package.propagate = True


class _HeldWarnings(logging.Handler):
    """The package's warnings while a command runs: printed after it when it succeeds, folded
    into the one error line when it fails (bad input is one line on stderr, whatever the
    library warned about on its way to the error)."""

    def __init__(self) -> None:
        super().__init__(logging.WARNING)
        self.records: list[logging.LogRecord] = []

    def emit(self, record: logging.LogRecord) -> None:
        self.records.append(record)

    def flush_to(self, stream) -> None:
        for r in self.records:
            stream.write(f"{r.name}: {r.getMessage()}\n")
        self.records.clear()

    def summary(self) -> str:
        if not self.records:
            return ""
        first = " ".join(self.records[0].getMessage().split())
        more = f" and {len(self.records) - 1} more" if len(self.records) > 1 else ""
        return f" (after the warning: {first}{more})"

if __name__ == "__main__":
    sys.exit(main())

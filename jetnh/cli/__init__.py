"""The ``jetnh`` command: derive, compare, simulate, connect, sweep and linearize
constrained systems; list the catalogue; run the benchmarks and the seed paper's
reproduction.

MODEL is a catalogue name (``jetnh models`` lists them; options as in ``n_trailer:N=4``)
or the path of a model file (TOML; see ``jetnh.modelfile`` and ``examples/*.toml``).

Exit codes: 0 ok, 1 model or numerical error, 2 usage, 3 the kernel cache cannot be
used (by ``jetnh cache warm``: nothing warmed; runs still work), 130 interrupted.  Errors print
a message on stderr, never a traceback (``--debug`` shows one for errors that are
jetnh's own bugs); warnings print ``jetnh: warning: ...`` on stderr (none with -q).
"""

from __future__ import annotations

import argparse
import os
import sys
import warnings

from ..errors import JetnhError, JetnhWarning
from .commands import COMMANDS
from .loading import load_model
from .parser import Formatter, option_name
from .progress import SIGN_OF_LIFE, Progress
from .usage import UsageError

__all__ = ["main", "build_parser", "Progress", "SIGN_OF_LIFE", "UsageError", "load_model",
           "option_name"]


def build_parser() -> argparse.ArgumentParser:
    from .. import __version__

    p = argparse.ArgumentParser(
        prog="jetnh", formatter_class=Formatter,
        description=__doc__.replace("``", ""),
        epilog="examples:\n"
               "  jetnh models\n"
               "  jetnh derive rolling_disk --principle suslov --format latex\n"
               "  jetnh compare examples/rolling_disk.toml\n"
               "  jetnh simulate knife_edge --t-end 5 --set alpha=0.5 --init phi_t=2 "
               "--plot knife.png\n"
               "  jetnh models chaplygin_sleigh --toml > sleigh.toml")
    p.add_argument("--version", action="version", version=f"jetnh {__version__}")
    p.add_argument("-q", "--quiet", action="store_true",
                   help="only errors on stderr: no progress, warnings or other messages "
                        "(also after COMMAND)")
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for command in COMMANDS:
        command.add_parser(sub)
    return p


def main(argv=None) -> int:
    # a closed stream (`2>&-`) is None in Python: write nothing there, never crash
    for name in ("stdout", "stderr"):
        if getattr(sys, name) is None:
            setattr(sys, name, open(os.devnull, "w"))
    parser = build_parser()
    args = parser.parse_args(argv)
    progress = Progress(quiet=getattr(args, "quiet", False))
    with warnings.catch_warnings():
        if progress.quiet:
            warnings.simplefilter("ignore")
        else:
            warnings.showwarning = _shown(progress, warnings.showwarning)
        return _run(args, progress)


def _shown(progress, python):
    """``warnings.showwarning`` for the command: a JetnhWarning as the command's own
    message (``jetnh: warning: ...``, no file, line or source), others as Python's."""
    def show(message, category, filename, lineno, file=None, line=None):
        if issubclass(category, JetnhWarning):
            progress.note(f"jetnh: warning: {message}")
        else:
            python(message, category, filename, lineno, file, line)
    return show


def _run(args, progress) -> int:
    """The command, its errors as messages and exit codes."""
    try:
        return args.func(args, progress)
    except UsageError as exc:
        print(f"jetnh {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except JetnhError as exc:            # a refused argument by the option that gave it
        print(f"jetnh: error: {exc.named(option_name(args, exc.argument))}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("jetnh: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        try:
            sys.stdout = open(os.devnull, "w")
        except OSError:
            pass
        return 0
    except OSError as exc:
        where = f" {exc.filename}" if getattr(exc, "filename", None) else ""
        print(f"jetnh: error:{where}: {exc.strerror or exc}", file=sys.stderr)
        return 1
    except (MemoryError, RecursionError) as exc:
        print(f"jetnh: error: the model is too large for this computation "
              f"({type(exc).__name__})", file=sys.stderr)
        return 1
    except Exception as exc:                                     # jetnh's own bugs
        if getattr(args, "debug", False):
            raise
        print(f"jetnh: internal error: {type(exc).__name__}: {exc}\n"
              "jetnh: this is a bug in jetnh; rerun with --debug for the traceback and "
              "report it", file=sys.stderr)
        return 1


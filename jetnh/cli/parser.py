"""The options the subcommands share: parent parsers (``COMMON`` for every command,
``PRINCIPLE`` for the commands that derive under a principle, ``RUN`` for those that
integrate a model) and the arguments of a model and of a shown result."""

from __future__ import annotations

import argparse
import math
import textwrap

from ..errors import PrincipleError
from ..mechanics import principles
from ..mechanics.principles import PRINCIPLES
from .loading import help_default
from .render import SCREEN_BUDGET
from .usage import UsageError

EPILOG_MODEL = ("MODEL: a catalogue name (see `jetnh models`; scalable ones take options, "
                "e.g. n_trailer:N=4) or a model file (TOML, e.g. examples/rolling_disk.toml).")


#: the steps of a fixed-step method without --steps
FIXED_STEPS = 1000

#: stands in an option's help for the default of its setting, looked up when the help is
#: shown (``shown_default``)
FALLBACK = "{default}"


class Formatter(argparse.HelpFormatter):
    """Each paragraph of a description or epilog (lines up to a blank or indented one)
    filled to the terminal's width, indented lines (examples) kept as written;
    ``FALLBACK`` in an option's help becomes its default, looked up only when the help is
    shown (the tolerances come from the numerics, which a command imports only when it
    runs)."""

    def _fill_text(self, text, width, indent):
        out, paragraph = [], []
        for line in text.splitlines() + [""]:
            if line and not line[0].isspace():
                paragraph.append(line.strip())
                continue
            if paragraph:
                out.append(textwrap.fill(" ".join(paragraph), width, initial_indent=indent,
                                         subsequent_indent=indent))
                paragraph = []
            out.append(indent + line if line else line)
        return "\n".join(out[:-1])

    def _get_help_string(self, action):
        text = super()._get_help_string(action)
        default = getattr(action, "default_shown", None)
        if not default:
            return text
        value = default()
        return text.replace(FALLBACK, str(value) if isinstance(value, int) else f"{value:g}")


def shown_default(action: argparse.Action, default) -> argparse.Action:
    """``action`` whose help shows ``default()`` in place of ``FALLBACK``."""
    action.default_shown = default
    return action


def jetnh_default(name):
    """The lookup of jetnh's default of the setting ``name`` (``loading.defaults``, as
    the help shows it: ``loading.help_default``)."""
    return lambda: help_default(name)


# ---------------------------------------------------------------------- value types
def _number(text: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None


def finite(text: str) -> float:
    """A finite number (no nan, no inf)."""
    v = _number(text)
    if not math.isfinite(v):
        raise argparse.ArgumentTypeError(f"{text!r} is not a finite number")
    return v


def seconds(text: str) -> float:
    """A duration: finite and > 0."""
    v = finite(text)
    if v <= 0:
        raise argparse.ArgumentTypeError(f"{text!r} is not a positive number of seconds")
    return v


def budget_seconds(text: str) -> float:
    """A duration from 0 (none) to an hour (the display's alarm timer)."""
    v = finite(text)
    if not 0 <= v <= 3600:
        raise argparse.ArgumentTypeError(f"{text!r} is not from 0 to 3600 seconds")
    return v


def count(text: str, low: int = 0) -> int:
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer") from None
    if v < low:
        raise argparse.ArgumentTypeError(f"{text!r} is below {low}")
    return v


def positive_count(text: str) -> int:
    return count(text, 1)


#: the most values an ``A:B:N`` range gives
MAX_RANGE = 100_000


def evenly_spaced(text: str, what: str, least: int, one: str = "",
                  otherwise: str = "") -> tuple[float, float, int]:
    """``A:B:N``, N evenly spaced values from A to B, as ``(A, B, N)``: A and B finite
    numbers (read by float(), never evaluated), N an integer from ``least`` (the command's
    rule: a scan needs 2 values, a grid axis 1) to ``MAX_RANGE``; A = B only for N = 1.
    ``what`` names the option in the messages, ``one`` says how to give the single value
    instead (``{a}`` standing for it), ``otherwise`` names the other form the option
    takes."""
    parts = text.split(":")
    try:
        if len(parts) != 3:
            raise ValueError
        a, b, n = float(parts[0]), float(parts[1]), int(parts[2])
    except ValueError:
        form = "A:B:N (N evenly spaced values from A to B; A and B numbers, N an integer)"
        raise UsageError(f"{what}: {text!r} is "
                         + (f"neither {form} nor {otherwise}" if otherwise else f"not {form}")
                         ) from None
    if not least <= n <= MAX_RANGE:
        raise UsageError(f"{what}: N must be from {least} to {MAX_RANGE}, got {n}")
    if not (math.isfinite(a) and math.isfinite(b)):
        raise UsageError(f"{what}: A and B must be finite numbers, got {text!r}")
    if a == b and n > 1:
        raise UsageError(f"{what}: {text!r} is a range of zero width ({n} equal values); "
                         "give A != B" + (", or " + one.format(a=f"{a:g}") if one else ""))
    return a, b, n


ALIASES = "aliases: " + "; ".join(f"{', '.join(p.aliases)} (= {p.name})"
                                  for p in principles.REGISTRY if p.aliases)


def canonical_principle(name: str) -> str:
    """--principle: an alias is read as its canonical name (argparse checks the choice)."""
    try:
        return principles.canonical(name)
    except PrincipleError:
        return name


def _common() -> argparse.ArgumentParser:
    common = argparse.ArgumentParser(add_help=False)
    common.add_argument("-q", "--quiet", action="store_true", default=argparse.SUPPRESS,
                        help="only errors on stderr: no progress or other messages")
    common.add_argument("--debug", action="store_true",
                        help="show a traceback for unexpected (internal) errors")
    return common


def principle_option(parser, default: str):
    """--principle (-p), its default described by ``default``."""
    parser.add_argument("--principle", "-p", choices=PRINCIPLES, type=canonical_principle,
                        default=None, metavar="NAME",
                        help=f"{', '.join(PRINCIPLES[:-1])} or {PRINCIPLES[-1]} (default: "
                             f"{default}); {ALIASES}")


def _principle() -> argparse.ArgumentParser:
    principle = argparse.ArgumentParser(add_help=False)
    principle_option(principle, "the model's, else chetaev: Lagrange-d'Alembert")
    principle.add_argument("--convention", choices=("paper", "imposed"), default=None,
                           help="paper: every variation is independent after the commutator "
                                "(as the paper); imposed: the variation's own condition is "
                                "imposed (default: the model's, else paper)")
    return principle


def span_options(parser):
    """--t-start and --t-end."""
    shown_default(parser.add_argument(
        "--t-start", type=float, default=None, metavar="T0",
        help="start time (default: the model's, else " + FALLBACK + ")"),
        jetnh_default("t_start"))
    parser.add_argument("--t-end", type=float, default=None, metavar="T",
                        help="end time (default: the model's: its [simulation] t_end; "
                             "every catalogue model has one)")


def tolerance_options(parser, default: str, rtol, atol, of="the adaptive methods"):
    """--rtol and --atol of the integration, their defaults described by ``default`` and
    looked up by ``rtol()`` and ``atol()`` (when the help is shown)."""
    for name, what, get in (("rtol", "relative", rtol), ("atol", "absolute", atol)):
        shown_default(parser.add_argument(
            f"--{name}", type=float, default=None, metavar=name.upper(),
            help=f"{what} tolerance of {of} (default: {default}" + FALLBACK + ")"), get)


def _run() -> argparse.ArgumentParser:
    run = argparse.ArgumentParser(add_help=False, parents=[PRINCIPLE])
    span_options(run)
    tolerance_options(run, "the model's, else ", jetnh_default("rtol"),
                      jetnh_default("atol"))
    run.add_argument("--steps", type=int, default=None, metavar="N",
                     help=f"steps of the fixed-step methods rk4, dla and dvi (default "
                          f"{FIXED_STEPS}); refused with the adaptive methods, which choose "
                          "their own steps (--max-steps bounds them)")
    shown_default(run.add_argument(
        "--max-steps", type=positive_count, default=None, metavar="N",
        help="step budget of a run: it stops after N steps and says where (default "
             + FALLBACK + ")"), lambda: help_default("max_steps"))
    return run


#: options of every subcommand
COMMON = _common()
#: options of the subcommands that derive under a principle (derive, linearize)
PRINCIPLE = _principle()
#: options of the subcommands that integrate a model (simulate, sweep): the principle's
#: and the run's
RUN = _run()

#: the library's argument names (``JetnhError.argument``) -> the destination and the
#: option of a command that sets them
ARGUMENT_OPTIONS = {"n_steps": ("steps", "--steps"), "rtol": ("rtol", "--rtol"),
                    "atol": ("atol", "--atol"), "timeout": ("timeout", "--timeout"),
                    "max_steps": ("max_steps", "--max-steps")}


def option_name(args, argument: str | None) -> str | None:
    """The option that gave the library's ``argument`` in this command line, else the
    argument's own name (the value came from elsewhere: a model file, a default)."""
    dest, option = ARGUMENT_OPTIONS.get(argument, (None, None))
    return option if dest and getattr(args, dest, None) is not None else argument


def subcommand(sub, name: str, run: bool = False, principle: bool = False,
               **kw) -> argparse.ArgumentParser:
    """The subparser ``name`` with the common options, and the run options if ``run``
    (else the principle's if ``principle``)."""
    parents = [COMMON] + ([RUN] if run else [PRINCIPLE] if principle else [])
    return sub.add_parser(name, parents=parents, formatter_class=Formatter, **kw)


def model_args(sp_, split=True):
    sp_.add_argument("model", metavar="MODEL", help="catalogue name or model file")
    if split:
        sp_.add_argument("--split", metavar="Q1,Q2",
                         help="dependent coordinates, comma-separated (overrides the "
                              "model's; e.g. --split x,y)")


def shown_args(sp_):
    sp_.add_argument("--format", choices=("text", "latex", "json"), default="text",
                     help="text (default), latex (an aligned block) or json; each "
                          "in the same shared form")
    sp_.add_argument("--out", metavar="FILE",
                     help="write the full result to FILE (on the screen large results "
                          f"are cut to about {SCREEN_BUDGET // 1000} kB)")
    sp_.add_argument("--simplify", type=budget_seconds, default=None, metavar="SECONDS",
                     help="trigsimp each small expression shown (at most 60 tree "
                          "nodes) within SECONDS, 10 x SECONDS in all; larger ones are "
                          "shown as derived, and a note says how many were simplified "
                          "(default: 0.5 for results shown without named quantities, "
                          "else 0; 0: none)")

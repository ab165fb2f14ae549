"""Command-line usage errors, and library messages in the words of the options."""

from __future__ import annotations

import re


class UsageError(Exception):
    """Bad command-line syntax (exit code 2)."""


#: Scene.run's argument names -> the options of simulate and sweep that set them
OPTION_NAMES = {"n_steps": "--steps", "rtol": "--rtol", "atol": "--atol",
                "timeout": "--timeout"}
_ARG_NAME = re.compile(r"(?<![\w-])(" + "|".join(OPTION_NAMES) + r")(?:=(?=\s|$))?(?!\w)")


def option_message(message: str) -> str:
    """An ``ArgumentError`` message with Scene.run's argument names as the CLI options."""
    return _ARG_NAME.sub(lambda m: OPTION_NAMES[m.group(1)], message)

"""Command-line usage errors."""


class UsageError(Exception):
    """Bad command-line syntax (exit code 2)."""

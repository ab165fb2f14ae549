"""The subcommands of ``jetnh``, one module each: ``add_parser(sub)`` declares its
options (and sets ``func=run``), ``run(args, progress)`` does it and returns the exit
code.  A new subcommand is a new module here, listed in ``COMMANDS``."""

from . import (bench, cache, compare, connect, derive, linearize, models, reproduce, simulate,
               sweep)

#: the subcommands in the order ``jetnh --help`` lists them
COMMANDS = (derive, compare, simulate, connect, sweep, linearize, models, bench, cache,
            reproduce)

"""``jetnh cache``: where the compiled-kernel cache lives and what it holds, empty it, or
compile the integrator loops into it ahead of the first run."""

from __future__ import annotations

import sys
import time

from ..parser import subcommand

#: the exit code of ``cache warm`` when the cache cannot be used: nothing is warmed, and
#: runs work all the same (each compiles its loop on first use); make's install step
#: accepts this code
UNUSABLE = 3


def add_parser(sub):
    k = subcommand(
        sub, "cache",
        help="show where the compiled-kernel cache lives and what it holds, empty it, "
             "or warm it",
        description="info: the cache directory (JETNH_CACHE, else the platform's user "
                    "cache directory), its entries and their size, and whether runs can "
                    "use it or fall back to a private temporary cache.  clear: remove "
                    "every cached kernel (they are compiled again when needed): only "
                    "directories jetnh made (they hold its marker file) are deleted.  "
                    "warm: compile the integrator loops a first run needs into it (make "
                    "does this once after installing), so that the first run loads them; "
                    f"exit code {UNUSABLE} when the cache cannot be used (nothing warmed; "
                    "runs still work, each compiling its loop on first use).")
    k.add_argument("action", choices=("info", "clear", "warm"), nargs="?", default="info",
                   help="default: info")
    k.add_argument("--all", action="store_true",
                   help="warm: every loop jetnh compiles ahead (with events, t_eval, dla, "
                        "dvi; a minute or more), not only those of a plain first run")
    k.set_defaults(func=run)


def _bytes(n: int) -> str:
    for unit in ("bytes", "KiB", "MiB", "GiB"):
        if n < 1024 or unit == "GiB":
            return f"{n} {unit}" if unit == "bytes" else f"{n:.1f} {unit}"
        n /= 1024


def run(args, progress) -> int:
    """Where the kernel cache lives and what it holds; empty it; or warm it."""
    from ...numeric.kernels import loader, store as cache

    if args.action == "warm":
        from ...numeric import precompile

        fallback = cache.info()["fallback"]
        if fallback:            # a temporary cache dies with its process: nothing to warm
            print(f"jetnh cache warm: error: nothing warmed: the kernel cache "
                  f"{cache.cache_root()} cannot be used ({fallback}); until it can, each "
                  "run compiles its loops on first use", file=sys.stderr)
            return UNUSABLE
        def report(name, seconds, loaded):
            progress.note(f"  {name:20s} {'loaded' if loaded else 'compiled'} in "
                          f"{seconds:.1f} s")

        tic = time.perf_counter()
        done = precompile.warm(list(precompile.LOOPS) if args.all else None,
                               report=report)
        print(f"{len(done)} integrator loops in {cache.cache_root()} "
              f"({time.perf_counter() - tic:.0f} s)")
        return 0
    if args.action == "clear":
        root = cache.cache_root()
        mine = cache.owned(root)
        n = loader.clear()
        print(f"removed {n} cached {'entry' if n == 1 else 'entries'} from {root}"
              if mine or not root.exists() else
              f"left {root} alone: it has no {cache.MARKER} file, so jetnh did not make it")
        return 0
    i = cache.info()
    print(f"kernel cache: {i['root']}"
          + (" (from JETNH_CACHE)" if i["env"] else " (the user cache directory)"))
    print(f"entries:      {i['entries']} ({_bytes(i['bytes'])})")
    if i["old_versions"]:
        print(f"older jetnh:  {_bytes(i['old_versions'])} of kernels of other versions "
              "(jetnh cache clear removes them)")
    if i["fallback"]:
        print(f"not usable:   {i['fallback']}")
        print("              runs use a private temporary cache, removed at exit")
    else:
        print("usable:       yes (runs keep their kernels here)")
    return 0

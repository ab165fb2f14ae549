"""``jetnh cache``: where the compiled-kernel cache lives and what it holds, or empty it."""

from __future__ import annotations

from ..parser import subcommand


def add_parser(sub):
    k = subcommand(
        sub, "cache",
        help="show where the compiled-kernel cache lives and what it holds, or empty it",
        description="info: the cache directory (JETNH_CACHE, else the platform's user "
                    "cache directory), its entries and their size, and whether runs can "
                    "use it or fall back to a private temporary cache.  clear: remove "
                    "every cached kernel (they are compiled again when needed): only "
                    "directories jetnh made (they hold its marker file) are deleted.")
    k.add_argument("action", choices=("info", "clear"), nargs="?", default="info",
                   help="default: info")
    k.set_defaults(func=run)


def _bytes(n: int) -> str:
    for unit in ("bytes", "KiB", "MiB", "GiB"):
        if n < 1024 or unit == "GiB":
            return f"{n} {unit}" if unit == "bytes" else f"{n:.1f} {unit}"
        n /= 1024


def run(args, progress) -> int:
    """Where the kernel cache lives and what it holds; or empty it."""
    from ...numeric.kernels import loader, store as cache

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

"""``jetnh models``: list the catalogue, show a model, or print it as a model file."""

from __future__ import annotations

from ..loading import load_model
from ..parser import subcommand
from ..usage import UsageError


def add_parser(sub):
    m = subcommand(
        sub, "models",
        help="list the catalogue, show a model, or print it as a model file",
        description="Without NAME: list the catalogue.  With NAME: its coordinates, "
                    "parameters, default initial state and docstring (source, closed forms, "
                    "first integrals); with --toml: the model as a model file to edit.")
    m.add_argument("name", nargs="?", metavar="NAME",
                   help="a catalogue name, with options for the scalable ones (e.g. "
                        "n_trailer:N=4)")
    m.add_argument("--toml", action="store_true", help="print NAME as a model file")
    m.set_defaults(func=run)


def run(args, progress) -> int:
    from ... import models
    from ...modelfile import dumps

    if args.toml and not args.name:
        raise UsageError("--toml prints one model as a model file: give its NAME (e.g. "
                         "jetnh models rolling_disk --toml)")
    if not args.name:
        width = max(map(len, models.CATALOGUE))
        for name in models.CATALOGUE:
            info = models.info(name)
            opts = "".join(f" [{k}={v}]" for k, v in info.options.items())
            print(f"{name:<{width}}  {info.summary}{opts}")
        print(f"\n{len(models.CATALOGUE)} models; `jetnh models NAME` shows one, "
              "`jetnh models NAME --toml` prints it as a model file.")
        return 0
    model = load_model(args.name)
    if args.toml:
        print(dumps(model), end="")
        return 0
    name = args.name.split(":")[0]
    doc = models.CATALOGUE[name].__doc__ if name in models.CATALOGUE else ""
    s = model.system
    print(f"{name}: {s.name}")
    print(f"  coordinates {', '.join(q.name for q in s.J.q)}; dependent "
          f"{', '.join(q.name for q in s.dependent)}")
    print(f"  parameters {', '.join(f'{k.name} = {v:g}' for k, v in s.defaults.items())}")
    print(f"  initial {', '.join(f'{k} = {v:g}' for k, v in model.initial.items())}")
    if doc:
        import textwrap
        print()
        print(textwrap.dedent("    " + doc.strip()))
    return 0

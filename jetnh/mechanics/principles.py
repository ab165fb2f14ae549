"""The four principles as values: one registry, looked up by name or alias.

A ``Principle`` says how its equations of motion are built from the composite action (12)
A = int (L + lambda_a f^a) dt of Zhao et al. (2008), and what they carry:

- ``variation``: the variation operator delta it varies with (``jetnh.mechanics.variations``);
- ``restricted``: the conventions in which eta is restricted to the Chetaev subspace
  ker(df/dqdot) (eta^alpha = Phi^alpha_mu eta^mu) before the coefficients of the eta's
  are taken; otherwise every eta^s counts as independent (the paper's convention);
  ``restricted_label``: the paper's label of the restricted equations;
- ``forms``: its forms of the equations, with the paper's equation labels;
- ``multipliers``/``reactions``: the prefixes of its multipliers, named after the
  dependent coordinates (lambda_x: states of the motion; nu_x: the algebraic reactions of
  Chetaev's multiplier form); a principle without multipliers varies L alone;
- ``kappa``: how the multipliers weigh the constraint Hessians in the acceleration rows
  (``jetnh.mechanics.accelerations``);
- ``discrete``: its structure-preserving discrete integrator, where there is one, for its
  equations in the ``discrete_conventions``.

The principles (section 3 of the paper):

- **chetaev** (Lagrange-d'Alembert; aliases "lagrange_dalembert", "dalembert",
  "nonholonomic"): Hoelder's variation (7), c = [d, delta] q = 0 with
  Chetaev's condition df^a/dqdot^s eta^s = 0, applied to L alone.  delta int L dt =
  int ([L]_s + Q_s) eta^s dt vanishes for every admissible eta, so eta is restricted
  first: P^T ([L] + Q) = 0 (Maggi), or [L]_s + Q_s + nu_a df^a/dqdot^s = 0 with reactions
  nu; discrete integrator "dla".
- **vakonomic** ("variational"): the vakonomic variation (5), c = 0 and delta f = 0, of
  the composite action, every eta independent: (15), (17), (18), (20), affine (36), (37);
  the multipliers are states; "dvi".
- **holder** ("hoelder", "hölder"): Hoelder's variation (7) of the composite action.  In
  the paper's convention every eta is independent, which gives the vakonomic equations
  (22) (and "dvi"); imposed, eta is restricted and lambda is left arbitrary.
- **suslov**: Suslov's variation (9), delta f = 0 with Chetaev's condition and the
  commutator (25)-(27), of the composite action with the explicit constraints: (29),
  (30), (31), affine (38); imposed, (30b) alone.  Its multipliers follow the motion
  without acting on it (kappa = -A_dep^-T p_dep).

``get(name_or_principle)`` returns the registered value; case, hyphens, dashes, spaces
and apostrophes do not matter in a name ("Lagrange-d'Alembert" is "lagrange_dalembert").
The public surface keeps taking the canonical strings ``PRINCIPLES`` (and every alias)
and reports canonical names.
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from ..errors import PrincipleError

CONVENTIONS = ("paper", "imposed")
#: prefixes of the symbols jetnh names after a coordinate q: lambda_q, nu_q, eta_q
NAMED = {"lambda": "the multiplier", "nu": "the reaction", "eta": "the variation"}


def named(prefix: str, coordinates) -> tuple[sp.Symbol, ...]:
    """The symbols ``<prefix>_<coordinate>`` (``NAMED``), one per coordinate."""
    return tuple(sp.Symbol(f"{prefix}_{q.name}") for q in coordinates)


def multiplier_symbols(system, prefix: str = "lambda") -> tuple[sp.Symbol, ...]:
    """One multiplier per constraint, named after the dependent coordinate it is solved
    for: lambda_<dependent[a]> multiplies the a-th constraint (``System.dependent`` is
    paired with ``System.constraints``), and qdot^a - phi^a in the explicit forms."""
    return named(prefix, system.dependent)


@dataclass(frozen=True)
class EquationForm:
    """One form of a principle's equations (a way of writing them, not a differential
    form): its name, the paper's label (and the label of its affine specialization,
    section 5), and whether it is built on the explicit constraints qdot^alpha - phi^alpha."""

    name: str
    paper: str = ""
    affine: str = ""
    explicit: bool = False

    def label(self, affine: bool) -> str:
        """The paper's label, with the affine one for affine constraints."""
        return f"{self.paper} {self.affine}" if affine and self.affine else self.paper


@dataclass(frozen=True)
class Principle:
    """One principle (see the module docstring); compare and hash by value."""

    name: str
    aliases: tuple[str, ...]
    variation: str
    restricted: tuple[str, ...]
    forms: tuple[EquationForm, ...]
    multipliers: str = ""
    reactions: str = ""
    kappa: str = "none"
    discrete: str = ""
    discrete_conventions: tuple[str, ...] = CONVENTIONS
    restricted_label: str = ""

    @property
    def has_multipliers(self) -> bool:
        """Whether the multipliers lambda are part of the composite action (and the state)."""
        return bool(self.multipliers)

    @property
    def multipliers_act(self) -> bool:
        """Whether the multipliers enter the accelerations q'' (vakonomic, Hoelder)."""
        return self.kappa == "multipliers"

    def form(self, name: str | None) -> EquationForm:
        """The form called ``name`` (the first form when None); PrincipleError otherwise."""
        if name is None:
            return self.forms[0]
        for f in self.forms:
            if f.name == name:
                return f
        raise PrincipleError(
            f"{self.name} has forms {tuple(f.name for f in self.forms)}, not {name!r}")

    def restricts(self, convention: str) -> bool:
        """Whether eta is restricted to the Chetaev subspace in ``convention``."""
        return convention in self.restricted

    def multiplier_symbols(self, system) -> tuple[sp.Symbol, ...]:
        """lambda_<dependent>, one per constraint; () without multipliers."""
        return multiplier_symbols(system, self.multipliers) if self.multipliers else ()

    def reaction_symbols(self, system) -> tuple[sp.Symbol, ...]:
        """nu_<dependent> (the reactions of the multiplier form); () without reactions."""
        return multiplier_symbols(system, self.reactions) if self.reactions else ()

    def integrator(self, convention: str = "paper") -> str:
        """The discrete integrator of this principle's equations in ``convention``, or ""."""
        return self.discrete if convention in self.discrete_conventions else ""

    def __str__(self):
        return self.name

    def __repr__(self):
        forms = ", ".join(f.name for f in self.forms)
        return (f"<Principle {self.name}: {self.variation} variation, forms {forms}"
                + (f", discrete {self.discrete}" if self.discrete else "") + ">")


_PROJECTED = (EquationForm("multiplier", "(15)"),
              EquationForm("explicit", "(17)", explicit=True),
              EquationForm("reduced", "(18)", "(36)", explicit=True),
              EquationForm("embedded", "(20)", "(37)", explicit=True))

CHETAEV = Principle(
    "chetaev", ("lagrange_dalembert", "dalembert", "nonholonomic"),
    variation="holder", restricted=CONVENTIONS,
    forms=(EquationForm("maggi"), EquationForm("multiplier"),
           EquationForm("voronets", explicit=True)),
    reactions="nu", discrete="dla")
VAKONOMIC = Principle(
    "vakonomic", ("variational",), variation="vakonomic", restricted=(),
    forms=_PROJECTED, multipliers="lambda", kappa="multipliers", discrete="dvi")
HOLDER = Principle(
    "holder", ("hoelder", "hölder"), variation="holder", restricted=("imposed",),
    forms=(EquationForm("multiplier", "(22)"), *_PROJECTED[1:]), multipliers="lambda",
    kappa="multipliers", discrete="dvi", discrete_conventions=("paper",))
SUSLOV = Principle(
    "suslov", (), variation="suslov", restricted=("imposed",),
    forms=(EquationForm("multiplier", "(29)", explicit=True),
           EquationForm("reduced", "(30)", "(38)", explicit=True),
           EquationForm("embedded", "(31)", "(38)", explicit=True)),
    multipliers="lambda", kappa="momenta", restricted_label="(30b)")

REGISTRY = (CHETAEV, VAKONOMIC, HOLDER, SUSLOV)
PRINCIPLES = tuple(p.name for p in REGISTRY)


def _key(name: str) -> str:
    """Case, hyphens, dashes, spaces and apostrophes do not matter in a name."""
    key = name.strip().lower()
    for ch in "-\u2013\u2014 ":
        key = key.replace(ch, "_")
    return key.replace("'", "").replace("\u2019", "")


_BY_NAME = {_key(n): p for p in REGISTRY for n in (p.name, *p.aliases)}


def get(principle) -> Principle:
    """The registered Principle of a name or alias (any case), or of a Principle."""
    if isinstance(principle, Principle) and principle in REGISTRY:
        return principle
    if isinstance(principle, str) and _key(principle) in _BY_NAME:
        return _BY_NAME[_key(principle)]
    return _unknown(principle)


def canonical(principle) -> str:
    """The canonical name of a principle given by name, alias or value."""
    return get(principle).name


def _unknown(principle):
    aliases = "; ".join(f"{p.name}: {', '.join(p.aliases)}" for p in REGISTRY if p.aliases)
    if isinstance(principle, Principle):
        raise PrincipleError(f"the principle {principle.name!r} is not one of jetnh's "
                             f"registered principles; use one of {PRINCIPLES}")
    if not isinstance(principle, str):
        raise PrincipleError(
            f"a principle is a name (str) or a jetnh.mechanics.principles.Principle, not a "
            f"{type(principle).__name__} ({principle!r:.80}); choose one of {PRINCIPLES}")
    raise PrincipleError(f"unknown principle {principle!r:.80}; choose one of {PRINCIPLES} "
                         f"(aliases {aliases})")

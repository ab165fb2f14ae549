"""The registry of principles: lookup by name, alias or value; what each entry claims about
its equations, checked against the derivation; every public surface takes aliases and
reports canonical names."""

import dataclasses
import random

import pytest
import sympy as sp
from hypothesis import given, settings, strategies as st

import jetnh as jn
import jetnh.strategies as jst
from jetnh.mechanics import accelerations, principles, variations
from jetnh.mechanics.equations import derive
from jetnh.mechanics.principles import REGISTRY
from numbers30 import f30, num

ALIASES = [(a, p.name) for p in REGISTRY for a in (p.name, *p.aliases)]
systems = jst.systems(min_n=2, max_n=3)


# ---------------------------------------------------------------------- lookup
def test_the_public_names_stay_the_four_canonical_strings():
    assert jn.PRINCIPLES == ("chetaev", "vakonomic", "holder", "suslov")
    assert tuple(p.name for p in REGISTRY) == jn.PRINCIPLES
    assert jn.Principle is principles.Principle


@st.composite
def spellings(draw):
    """An alias as a user may type it: any case, '-' / ' ' / '_' interchanged, padded."""
    alias, name = draw(st.sampled_from(ALIASES))
    chars = []
    for ch in alias:
        if ch in "-_ ":
            ch = draw(st.sampled_from("-_ "))
        elif ch.isalpha() and draw(st.booleans()):
            ch = ch.upper()
        chars.append(ch)
    pad = draw(st.sampled_from(["", " ", "  "]))
    return pad + "".join(chars) + pad, name


@given(spellings())
def test_every_alias_resolves_to_its_canonical_principle(case):
    text, name = case
    p = principles.get(text)
    assert p.name == name and p is principles.get(name) and principles.get(p) is p
    assert principles.canonical(text) == name


def test_the_documented_aliases():
    want = {"lagrange_dalembert": "chetaev", "Lagrange-d'Alembert": "chetaev",
            "Lagrange\u2013d\u2019Alembert": "chetaev", "nonholonomic": "chetaev",
            "variational": "vakonomic", "hoelder": "holder", "Hölder": "holder"}
    assert {k: principles.canonical(k) for k in want} == want
    assert len({principles._key(a) for p in REGISTRY for a in (p.name, *p.aliases)}) == \
        sum(1 + len(p.aliases) for p in REGISTRY)                  # no alias is shared


def test_unknown_principles_name_the_choices():
    with pytest.raises(jn.PrincipleError) as e:
        principles.get("hamilton")
    msg = str(e.value)
    assert "unknown principle 'hamilton'" in msg
    assert all(n in msg for n in jn.PRINCIPLES) and "lagrange_dalembert" in msg
    with pytest.raises(jn.PrincipleError, match="a principle is a name .*not a int"):
        principles.get(3)
    with pytest.raises(jn.PrincipleError, match="not one of jetnh's registered"):
        principles.get(dataclasses.replace(principles.CHETAEV, name="mine"))
    with pytest.raises(jn.PrincipleError, match="chetaev has forms .*'maggi'"):
        principles.CHETAEV.form("reduced")
    long = "x" * 500
    assert len(str(pytest.raises(jn.PrincipleError, principles.get, long).value)) < 400


def test_principles_are_immutable_values():
    p = principles.get("chetaev")
    with pytest.raises(dataclasses.FrozenInstanceError):
        p.name = "other"
    assert p == dataclasses.replace(p) and hash(p) == hash(dataclasses.replace(p))
    assert str(p) == "chetaev"
    assert repr(p) == ("<Principle chetaev: holder variation, forms maggi, multiplier, "
                       "voronets, discrete dla>")


# ---------------------------------------------------------------------- entries
def test_each_entry_names_operators_that_exist():
    for p in REGISTRY:
        assert p.variation in variations.KINDS
        assert p.kappa in accelerations.KAPPA
        assert set(p.restricted) <= set(principles.CONVENTIONS)
        assert p.discrete in ("", "dla", "dvi")
    assert principles.CHETAEV.variation == "holder" and principles.CHETAEV.restricted == \
        principles.CONVENTIONS
    assert [p.integrator(c) for p in REGISTRY for c in principles.CONVENTIONS] == [
        "dla", "dla", "dvi", "dvi", "dvi", "", "", ""]


def test_the_paper_labels_of_the_forms():
    """The labels as the paper numbers them (sections 3 and 5), written out once more."""
    want = {"vakonomic": "multiplier (15), explicit (17), reduced (18) (36), embedded (20) (37)",
            "holder": "multiplier (22), explicit (17), reduced (18) (36), embedded (20) (37)",
            "suslov": "multiplier (29), reduced (30) (38), embedded (31) (38)",
            "chetaev": "maggi, multiplier, voronets"}
    got = {p.name: ", ".join(f"{f.name} {f.label(affine=True)}".strip() for f in p.forms)
           for p in REGISTRY}
    assert got == want
    assert principles.SUSLOV.restricted_label == "(30b)"


@settings(max_examples=8)
@given(systems)
def test_what_each_entry_claims_holds_for_its_equations(system):
    """restricted: one row per independent coordinate; the paper's labels of the forms;
    has_multipliers: multiplier states lambda_<dependent>; reactions nu_<dependent>;
    multipliers that do not act are absent from the accelerations q''."""
    J, n, k = system.J, system.J.n, system.k
    lam_names = tuple(f"lambda_{d.name}" for d in system.dependent)
    for p in REGISTRY:
        for conv in principles.CONVENTIONS:
            for f in p.forms:
                eom = system.equations(p.name, f.name, conv)
                restricted = p.restricts(conv) and (p.has_multipliers or f.name == "maggi")
                assert len(eom) == (n - k if restricted else n if p.has_multipliers
                                    else len(eom)), (p.name, f.name, conv)
                assert eom.explicit == f.explicit
                assert eom.paper == (p.restricted_label if restricted
                                     else f.label(system.is_affine))
                assert tuple(m.name for m in eom.multipliers) == (
                    lam_names if p.has_multipliers and not restricted else ())
                assert tuple(m.name for m in eom.arbitrary) == (
                    lam_names if restricted and p.multipliers_act else ())
                assert tuple(m.name for m in eom.reactions) == (
                    tuple(f"nu_{d.name}" for d in system.dependent)
                    if p.reactions and f.name == "multiplier" else ())
        eom = system.equations(p.name)
        if not p.multipliers_act:
            acc = eom.accelerations()
            assert not set(eom.multipliers) & set().union(
                *(acc[a].free_symbols for a in J.qdd))


def test_acting_multipliers_move_the_accelerations():
    from jetnh import models

    s = models.get("rolling_disk")
    J = s.J
    rnd = random.Random(5)
    point = {x: f30(rnd.uniform(-1, 1)) for x in (J.t, *J.q, *s.independent_velocities)}
    point.update({x: f30(v) for x, v in s.defaults.items()})
    point.update({v: num(e, point) for v, e in s.phi.items()})
    for p in REGISTRY:
        eom = s.equations(p.name)
        acc = eom.accelerations()
        q2 = [[num(acc[a], {**point, **{m: f30(rnd.uniform(-1, 1)) for m in eom.multipliers}})
               for a in J.qdd] for _ in range(2)]
        moved = max(abs(x - y) for x, y in zip(*q2)) > 1e-12
        assert moved == p.multipliers_act, p.name


@settings(max_examples=6)
@given(systems, st.sampled_from(ALIASES), st.sampled_from(principles.CONVENTIONS))
def test_an_alias_derives_what_its_canonical_name_derives(system, alias_name, convention):
    alias, name = alias_name
    p = principles.get(name)
    for form in (None, p.forms[-1].name):
        a = derive(system, alias, form, convention)
        b = system.equations(name, form, convention)
        c = system.equations(p, form, convention)
        for e in (a, c):
            assert e.principle == name and e.form == b.form and e.paper == b.paper
            assert e.multipliers == b.multipliers and e.reactions == b.reactions
            assert e.expressions == b.expressions
    assert a.accelerations() == b.accelerations()


def test_chetaev_is_hoelders_variation_of_L_alone_restricted():
    """Second route to the Maggi form: the coefficients of the independent eta^mu in
    ([L]_s + Q_s) eta^s with eta^alpha = Phi^alpha_mu eta^mu, written out here."""
    from jetnh import models

    s = models.get("knife_edge")
    J = s.J
    eom = s.equations("lagrange_dalembert", "maggi")
    EL = J.euler(s.L)
    Phi = s.Phi
    want = [EL[i] + sum((Phi[a, m] * EL[j] for a, j in enumerate(s.dep_index)), sp.S.Zero)
            for m, i in enumerate(s.ind_index)]
    rnd = random.Random(3)
    point = {x: f30(rnd.uniform(-1, 1)) for x in (J.t, *J.q, *J.qd, *J.qdd)}
    point.update({sym: f30(rnd.uniform(0.5, 1.5)) for sym in s.parameters})
    for got, exp in zip(eom.expressions, want):
        assert abs(num(got, point) - num(exp, point)) < 1e-25


# ---------------------------------------------------------------------- surfaces
def test_the_integrals_and_symmetries_take_aliases_and_report_canonical_names():
    from jetnh import models

    s = models.get("nonholonomic_particle")
    assert [str(i) for i in jn.conserved_quantities(s, "variational", degree=1)] == \
        [str(i) for i in jn.conserved_quantities(s, "vakonomic", degree=1)]
    syms = jn.lie_symmetries(s, "Lagrange-d'Alembert")
    assert syms and all(x.principle == "chetaev" for x in syms)
    assert all(x.principle == "chetaev" for x in jn.noether_symmetries(s, "nonholonomic"))


def test_model_files_and_the_command_line_take_aliases():
    from jetnh import modelfile, models
    from jetnh.cli import build_parser

    s = models.get("rolling_disk")
    text = modelfile.dumps(s, principle="hölder")
    assert 'principle = "holder"' in text
    assert modelfile.loads(text.replace('"holder"', '"Hoelder"')).principle == "holder"
    with pytest.raises(jn.ModelFileError, match="'principle' must be one of chetaev"):
        modelfile.loads(text.replace('"holder"', '"hamilton"'))
    args = build_parser().parse_args(["derive", "rolling_disk", "-p", "lagrange-d'alembert"])
    assert args.principle == "chetaev"
    help_text = " ".join(build_parser()._subparsers._group_actions[0].choices["simulate"]
                         .format_help().split())
    assert "nonholonomic" in help_text and "chetaev, vakonomic, holder or suslov" in help_text


def test_a_scene_takes_an_alias_and_reports_the_canonical_name():
    from jetnh import models

    s = models.get("rolling_disk")
    lams = principles.multiplier_symbols(s)
    state = dict.fromkeys((*s.J.q, *s.independent_velocities), 0.5)
    scene = jn.Scene(s, "variational", initial={**state, **dict.fromkeys(lams, 0.1)})
    assert scene.principle == "vakonomic"
    assert scene.multipliers == tuple(m.name for m in lams)
    assert jn.Scene(s, principles.CHETAEV, initial=state).multipliers == ()
    with pytest.raises(jn.PrincipleError, match="unknown principle"):
        jn.Scene(s, "hamilton", initial=state)

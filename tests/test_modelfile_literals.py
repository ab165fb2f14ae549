"""Model-file numbers: integers and decimals only, and never a nonzero literal read as 0
or as a subnormal (its term would vanish or lose digits)."""

import pytest
from hypothesis import given, settings, strategies as st

from jetnh import modelfile
from jetnh.errors import ModelFileError

BASE = ('coordinates = ["x", "y", "z"]\n'
        'lagrangian = "(x_t**2 + y_t**2 + z_t**2)/2 - k*x**2/2"\n')


def _model(coefficient="1", k="1.0"):
    return modelfile.loads(BASE + f'constraints = ["z_t - {coefficient}*y*x_t"]\n'
                           f"[parameters]\nk = {k}\n")


@pytest.mark.parametrize("text", ["1e-400", "1e-320", "-2.5e-330", "0.000001e-310"])
def test_underflow_refused(text):
    with pytest.raises(ModelFileError, match="below double precision.*rescale the units"):
        _model(coefficient=text.lstrip("-"))
    with pytest.raises(ModelFileError, match="below double precision") as e:
        _model(k=text)
    assert text in str(e.value)


@pytest.mark.parametrize("text", ["0x10", "0b11", "0o7", "1_0", "1_000.5"])
def test_other_notations_refused(text):
    with pytest.raises(ModelFileError, match="integers and decimals") as e:
        _model(coefficient=text)
    assert text in str(e.value)


@settings(deadline=None, max_examples=25)
@given(st.integers(-300, 300), st.integers(1, 9))
def test_scaled_literals_kept(exponent, digit):
    """A coefficient d e<exp> anywhere in the normal range is read as written, in an
    expression and as a parameter; 0 itself stays 0."""
    text = f"{digit}e{exponent}"
    m = _model(coefficient=text, k=text)
    assert [float(v) for v in m.system.defaults.values()] == [float(text)]
    (c,) = m.system.constraints
    # c = z_t - a y x_t: a at y = x_t = 1, z_t = 0
    a = -float(c.subs({s: (0 if s.name == "z_t" else 1) for s in c.free_symbols}))
    assert a == pytest.approx(float(text), rel=1e-15)
    assert _model(coefficient="0.0", k="0.0").system.is_integrable()

"""Catalogue names take options as the command line and ``Model.name`` spell them,
``name:K=V,...``; a wrong spelling is refused saying how to give them."""

import pytest

from jetnh import models
from jetnh.errors import ModelFileError


def test_name_with_options_equals_keywords():
    by_name = models.get("n_trailer:N=3")
    assert by_name == models.get("n_trailer", N=3)
    assert len(by_name.dependent) == 4
    m = models.model("n_trailer:N=3")
    assert m.name == "n_trailer:N=3"
    assert models.model(m.name).system == m.system
    assert models.initial("particle_chain:N=4") == models.initial("particle_chain", N=4)
    assert models.info("n_trailer:N=3") is models.info("n_trailer")


@pytest.mark.parametrize("name, says", [
    ("n_trailer:16", "'n_trailer:N=16' or get('n_trailer', N=16)"),
    ("n_trailer:N=x", "must be an integer"),
    ("n_trailer:M=3", "has no option M"),
    ("rolling_disk:N=2", "has no option N"),
    ("nope:N=2", "no model named 'nope'"),
])
def test_wrong_spellings_say_how(name, says):
    with pytest.raises(ModelFileError) as err:
        models.model(name)
    assert says in str(err.value)


def test_option_given_twice():
    with pytest.raises(ModelFileError, match="given twice"):
        models.get("n_trailer:N=3", N=4)


def test_unknown_name_hints_at_the_options():
    from jetnh.models import _entry

    with pytest.raises(ModelFileError, match=r"get\('n_trailer', N=4\)"):
        _entry("n_trailer:N=3")

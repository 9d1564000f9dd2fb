"""ikteach.course.claims: the one-line verdicts printed after a notebook's claims."""
import numpy as np
import pytest

from ikteach.course.claims import claim


def test_line_names_the_numbers_and_the_verdict(capsys):
    assert claim("DLS stops first", True, dls=7, pinv=12, jt=43) is True
    assert claim("no numbers", 0) is False
    assert capsys.readouterr().out == ("claim: DLS stops first (dls=7, pinv=12, jt=43): True\n"
                                       "claim: no numbers: False\n")


def test_reals_are_rounded_integers_bools_and_text_kept(capsys):
    claim("x", np.bool_(True), a=0.123456, b=np.float64(9.8765e-11), c=np.int64(1000), d=False, e="[4, 7]")
    claim("x", True, f=4.0, g=-0.0, h=float("inf"), i=-1e-20, j=float("nan"))
    assert capsys.readouterr().out == ("claim: x (a=0.123, b=9.88e-11, c=1000, d=False, e=[4, 7]): True\n"
                                       "claim: x (f=4, g=0, h=inf, i=-1e-20, j=nan): True\n")


def test_rounding_hides_last_bit_noise(capsys):
    a, b = 0.1 + 0.2, 0.3  # differ in the last bit, as two BLAS kernels may
    claim("x", True, v=a)
    claim("x", True, v=b)
    first, second = capsys.readouterr().out.splitlines()
    assert a != b and first == second == "claim: x (v=0.3): True"


@pytest.mark.parametrize("text", ["", 3, None])
def test_bad_text_names_the_parameter(text):
    with pytest.raises(ValueError, match="^text:"):
        claim(text, True)

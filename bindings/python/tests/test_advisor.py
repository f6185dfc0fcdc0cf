# SPDX-License-Identifier: Apache-2.0
"""The leveler advisor from Python: a leveler file and its errors, the
advice against the exact bounded minimiser of a one-actuator problem,
identification of a known G and its refusal."""

import numpy as np
import pytest

import flatline

LEVELER = """{ "format": "flatline-leveler", "version": 1, "name": "python test",
  "zones": 3,
  "actuators": [
    { "name": "entry gap", "unit": "mm", "min": -3, "max": 3, "step": 0.5 },
    { "name": "tilt", "unit": "mm", "min": -2, "max": 2, "step": 0.3 } ],
  "influence": [ [ 4.0, -6.0 ],
                 [ -8.0, 0.0 ],
                 [ 4.0, 6.0 ] ],
  "target": [ 0, 2, 0 ] }
"""


def test_leveler_file():
    a = flatline.Advisor.loads(LEVELER)
    assert (a.zones, a.actuators) == (3, 2)
    assert a.actuator(1) == flatline.Actuator("tilt", "mm", -2.0, 2.0, 0.3)
    np.testing.assert_array_equal(a.influence, [[4, -6], [-8, 0], [4, 6]])
    fit = a.fit
    assert (fit.r_squared, fit.rms_i_units, fit.steps) == (1.0, 0.0, 0)
    # The file's target: a profile equal to it (plus any level) needs nothing.
    advice = a.advise([10, 12, 10], [0, 0])
    assert np.all(np.abs(advice.delta) < 1e-12)


def test_leveler_file_from_a_path(tmp_path):
    path = tmp_path / "lévelér.json"
    path.write_text(LEVELER, encoding="utf-8")
    assert flatline.Advisor.load(path).zones == 3
    with pytest.raises(flatline.FileError):
        flatline.Advisor.load(tmp_path / "missing.json")


def test_leveler_file_errors_name_field_and_line():
    bad = LEVELER.replace("[ -8.0, 0.0 ]", "[ -8.0 ]")
    with pytest.raises(flatline.FormatError, match=r"'influence\[1\]' \(line 7\)"):
        flatline.Advisor.loads(bad)


def test_advice_is_the_bounded_minimiser():
    # One actuator, so the bounded minimiser is the unconstrained one
    # clipped to the box: d = clip(-gain g.r / (g.g + lambda), lo, hi),
    # with g and r without their means and lambda = damping g.g.
    a = flatline.Advisor(4, 1, advisor_damping=0.1, advisor_gain=0.5)
    a.set_actuator(0, "tilt", "mm", -1.0, 1.0, 0.25)
    g = np.array([[-3.0], [-1.0], [1.0], [3.0]])
    a.influence = g
    gc = g[:, 0] - g[:, 0].mean()
    for p, u in (([0, 0, 1, 2], 0.0), ([3, 1, 0, 0], 0.9), ([0, 0, 0, 0.5], -0.2)):
        r = np.asarray(p, float) - np.mean(p)
        d_free = -0.5 * gc @ r / (gc @ gc * 1.1)
        lo, hi = max(-1.0 - u, -0.25), min(1.0 - u, 0.25)
        advice = a.advise(p, [u], [u])
        # One division and a few sums of small integers.
        assert advice.delta[0] == pytest.approx(np.clip(d_free, lo, hi), abs=1e-12)
        assert -1.0 <= u + advice.delta[0] <= 1.0
        np.testing.assert_allclose(advice.predicted, p + gc * advice.delta[0], atol=1e-12)
        on_bound = advice.delta[0] in (lo, hi)
        assert advice.confidence == pytest.approx(0.5 if on_bound else 1.0)


def test_identification_recovers_g_and_refuses_noise():
    rng = np.random.default_rng(4)
    g = rng.uniform(-10, 10, (12, 3))
    du = rng.uniform(-1, 1, (30, 3))
    sigma = 0.2
    dp = du @ g.T + sigma * rng.standard_normal((30, 12))
    a = flatline.Advisor(12, 3)
    fit = a.identify(du, dp)
    assert fit.steps == 30 and fit.r_squared > 0.99
    # Standard errors sigma sqrt([(U^T U)^-1]_jj); 5 of them over 36 entries.
    se = sigma * np.sqrt(np.diag(np.linalg.inv(du.T @ du)))
    err = np.abs(a.influence - (g - g.mean(axis=0)))
    assert np.all(err <= 5 * se)
    for j in range(3):
        a.set_actuator(j, f"u{j}", "mm", -1, 1, 0.5)
    a.advise(np.zeros(12), np.zeros(3))
    with pytest.raises(flatline.NumericError, match="R\\^2"):
        a.identify(du, 3.0 * rng.standard_normal((30, 12)))
    assert a.fit.r_squared < flatline._advisor.MIN_R_SQUARED
    with pytest.raises(flatline.StateError, match="refused"):
        a.advise(np.zeros(12), np.zeros(3))


def test_bad_arguments():
    a = flatline.Advisor.loads(LEVELER)
    with pytest.raises(ValueError, match="g.shape\\[0\\]"):
        a.influence = np.zeros((4, 2))
    with pytest.raises(flatline.InvalidArgumentError, match="'profile_count'"):
        a.advise([1, 2], [0, 0])
    with pytest.raises(flatline.InvalidArgumentError, match="outside the range"):
        a.advise([1, 2, 3], [0, 0], [5, 0])
    with pytest.raises(flatline.InvalidArgumentError, match="advisor_gain"):
        flatline.Advisor(3, 2, advisor_gain=0)
    with pytest.raises(TypeError, match="another component"):
        flatline.Advisor.loads(LEVELER, flat_zone_width=100)
    with pytest.raises(TypeError):
        flatline.Advisor(3.5, 2)


def test_zone_without_data():
    a = flatline.Advisor.loads(LEVELER)
    advice = a.advise([10, np.nan, 10], [0, 0])
    assert np.isnan(advice.predicted[1]) and not np.isnan(advice.predicted[0])
    assert np.all(np.isfinite(advice.delta))


def test_options():
    assert flatline.advisor_options() == {"advisor_damping": 0.01, "advisor_gain": 0.5}

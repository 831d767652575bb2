import json

import numpy as np
import pytest

from fdemtools import ductility
from fdemtools.common import ToolError


@pytest.mark.parametrize("true", [
    (2.0, -1.5, 0.5, 0.3),
    (8.0, -3.0, 1.2, -0.2),   # two decays
    (5.5, -2.2, -1.0, 0.4),   # mixed signs
])
def test_recovers_known_coefficients_noise_free(true):
    x = np.linspace(0.15, 1.25, 9)  # MPa, the [K25] precompression range
    y = ductility.model(x, *true)
    r = ductility.fit(x, y)
    got = (r["a"], r["b"], r["c"], r["d"])
    assert got == pytest.approx(true, rel=1e-9)
    assert r["relative_residual"] < 1e-10
    for k, v in zip("abcd", true):
        lo, hi = r["bounds"][k]
        assert lo <= v <= hi or abs(hi - lo) < 1e-6 * max(1, abs(v))


def test_bounds_cover_truth_and_scale_with_noise():
    true = (6.0, -2.5, 1.0, 0.2)
    x = np.linspace(0.1, 1.4, 14)
    y0 = ductility.model(x, *true)
    widths = []
    for sigma in (0.01, 0.04):
        rng = np.random.default_rng(42)
        r = ductility.fit(x, y0 + sigma * rng.standard_normal(len(x)))
        widths.append(r["bounds"]["a"][1] - r["bounds"]["a"][0])
        for k, v in zip("abcd", true):
            lo, hi = r["bounds"][k]
            assert lo < v < hi, (k, lo, v, hi)
        # same noise pattern, four times the amplitude: linearised bounds scale by about four
    assert widths[1] / widths[0] == pytest.approx(4.0, rel=0.25)


def test_bounds_match_linear_theory_where_the_model_is_linear():
    # with the rates fixed at their true values the model is linear in (a, c); the covariance for (a, c) from
    # the full fit must match s^2 (M^T M)^-1 only approximately, but the t quantile must be the n-4 one.
    x = np.linspace(0, 1, 10)
    y = ductility.model(x, 1.0, -1.0, 2.0, 0.5) + 0.001 * np.sin(37 * x)
    r = ductility.fit(x, y)
    from scipy import stats
    assert r["dof"] == 6
    assert r["t_quantile"] == pytest.approx(stats.t.ppf(0.975, 6), rel=1e-12)


def test_four_points_exact_fit_no_bounds():
    true = (2.0, -1.5, 0.5, 0.3)
    x = np.array([0.15, 0.5, 1.0, 1.25])
    r = ductility.fit(x, ductility.model(x, *true))
    assert r["bounds"] is None and "no degrees of freedom" in r["bounds_note"]
    assert ductility.model(x, r["a"], r["b"], r["c"], r["d"]) == pytest.approx(ductility.model(x, *true), rel=1e-8)


def test_too_few_points():
    with pytest.raises(ToolError, match="at least 4 points"):
        ductility.fit([0.1, 0.2, 0.3], [3, 2, 1])


def test_cli(tmp_path, cli):
    true = (2.0, -1.5, 0.5, 0.3)
    x = np.linspace(0.15, 1.25, 7)
    y = ductility.model(x, *true)
    f = tmp_path / "mu.csv"
    f.write_text("sigma_MPa,mu\n" + "".join(f"{a!r},{b!r}\n" for a, b in zip(x, y)))
    rc, out, err = cli("ductility-fit", f)
    assert rc == 0, err
    r = json.loads((tmp_path / "mu_fit.json").read_text())
    assert (r["a"], r["b"], r["c"], r["d"]) == pytest.approx(true, rel=1e-6)
    assert (tmp_path / "mu_fit.png").exists() and (tmp_path / "mu_fit.svg").exists()
    rc, out, err = cli("ductility-fit", f, "--y", "ductility")
    assert rc == 1 and "no column 'ductility'" in err and "Traceback" not in err


def test_cli_from_eeep_results(tmp_path, cli):
    true = (2.0, -1.5, 0.5, 0.3)
    pts = []
    for i, s in enumerate(np.linspace(0.15, 1.25, 6)):
        p = tmp_path / f"e{i}.json"
        p.write_text(json.dumps({"ductility": float(ductility.model(s, *true))}))
        pts += ["--point", f"{s!r}={p}"]
    rc, out, err = cli("ductility-fit", *pts, "--out", tmp_path / "fit")
    assert rc == 0, err
    r = json.loads((tmp_path / "fit.json").read_text())
    assert (r["a"], r["b"], r["c"], r["d"]) == pytest.approx(true, rel=1e-6)
    rc, out, err = cli("ductility-fit", "--point", f"0.5={tmp_path / 'missing.json'}")
    assert rc == 1 and "cannot read" in err

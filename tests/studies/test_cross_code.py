"""floatsim against other codes on open multi-code data (docs/accuracy.md, "Against other codes").

RM3 on WEC-Sim's three chains (the preset rm3-wecsim-moorings: WEC-Sim's WAMIT coefficients, its chains with their
buoys on MoorDyn, its sea as it ran) against the statistics of WEC-Sim's own run (assets/reference/rm3_mooring.json).

The F3OF decay tests (assets/scenes/f3of/, run as `floatsim run` runs them) against the statistics of WEC-Sim, InWave,
WaveDyn, ProteusDS and HydroChrono derived from SEA-Stack's records (assets/reference/f3of_decay.json). floatsim's
platform is rebuilt from SEA-Stack's meshes and solved by Capytaine, theirs from their own solves: a spread of a few
per cent among the codes is theirs too.
"""

import numpy as np
import pytest

from studies.f3of import SIGNALS, compare, mean_period, run

pytestmark = pytest.mark.slow

SPREAD = 0.015
"""How far past the five codes' range floatsim's period may fall (their own spread: 3.4 % in DT1, 2 % in DT2, 3.6 % in DT3)."""


@pytest.fixture(scope="module")
def rows(tmp_path_factory):
    folder = tmp_path_factory.mktemp("f3of")
    return compare({test: run(test, folder) for test in ("DT1", "DT2", "DT3")})


def _range(row, free_only: bool) -> tuple[float, float]:
    """The codes' mean periods; `free_only`: without HydroChrono, which holds the base to the test's one dof."""
    periods = [mean_period(s) for name, s in row["codes"].items() if s["periods"] and not (free_only and name == "HydroChrono")]
    return min(periods), max(periods)


RELEASED = [k for k, s in enumerate(SIGNALS) if s.name != "other flap"]
"""The bodies released (the other flap's first cycles are its start, driven by the first one's waves)."""


@pytest.mark.parametrize("k", RELEASED, ids=[f"{SIGNALS[k].test} {SIGNALS[k].name}" for k in RELEASED])
def test_each_decay_period_falls_among_the_other_codes(rows, k):
    """The mean period of the first three cycles within the codes' range, widened by SPREAD. DT2 against the four that
    let the base surge and heave too, as floatsim's planar joint does (HydroChrono's pitch-only base swings at 8.2 s)."""
    row = rows[k]
    lo, hi = _range(row, free_only=row["signal"].test == "DT2")
    ours = mean_period(row["floatsim"])
    assert lo * (1 - SPREAD) <= ours <= hi * (1 + SPREAD), (row["signal"], ours, lo, hi)


@pytest.mark.parametrize("k", range(len(SIGNALS)), ids=[f"{s.test} {s.name}" for s in SIGNALS])
def test_the_first_swings_match_the_other_codes_in_sign_and_size(rows, k):
    """The first two extrema after the release: the same sign as every code's and a size within the codes' range,
    widened by 10 % of the largest (the released body loses a few per cent a cycle to its waves; the other flap is
    driven by them)."""
    row = rows[k]
    ours = np.array(row["floatsim"]["extrema"][:2])[:, 1]
    for name, stats in row["codes"].items():
        if stats["extrema"]:
            assert np.array_equal(np.sign(ours), np.sign(np.array(stats["extrema"][:2])[:, 1])), name
    theirs = np.array([np.array(s["extrema"][:2])[:, 1] for n, s in row["codes"].items() if s["extrema"] and n != "HydroChrono"])
    slack = 0.1 * np.abs(theirs).max()
    assert np.all(np.abs(ours) >= np.abs(theirs).min(axis=0) - slack) and np.all(np.abs(ours) <= np.abs(theirs).max(axis=0) + slack)


@pytest.fixture(scope="module")
def rm3(tmp_path_factory):
    from studies.rm3_mooring import compare, run

    return {row["name"]: row for row in compare(run(tmp_path_factory.mktemp("rm3")))}


TENSIONS = ("line 4 tension", "line 5 tension", "line 6 tension")


@pytest.mark.parametrize("name", TENSIONS)
def test_rm3s_chains_pull_as_wec_sims_on_average(rm3, name):
    """The mean fairlead tension over 100-400 s within 3 % of WEC-Sim's 169.3-169.4 kN (the still-water statics
    give 169.3 kN in both; floatsim's spar also drifts 0.1-0.2 m down-wave, which WEC-Sim's does not: docs/accuracy.md)."""
    row = rm3[name]
    assert row["floatsim"]["mean"] == pytest.approx(row["WEC-Sim"]["mean"], rel=0.03)


@pytest.mark.parametrize("name, within", [("float heave", 0.05), *((t, 0.10) for t in TENSIONS), ("plate heave", 0.40)])
def test_rm3s_response_to_wec_sims_sea_is_wec_sims(rm3, name, within):
    """The standard deviation over 100-400 s: the float's heave within 5 % of WEC-Sim's, the tensions within 10 %
    (floatsim's spar has more slow surge), the plate's heave within 40 % (floatsim's is 30 % larger, in the waves'
    band too: a finding, docs/accuracy.md). A sign, unit or phase error in the imported coefficients or the sea moves
    each by far more."""
    row = rm3[name]
    assert row["floatsim"]["std"] == pytest.approx(row["WEC-Sim"]["std"], rel=within)

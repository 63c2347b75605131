"""Settings whose cost grows are checked against stated limits before anything is allocated; the
message names the estimated memory and the flag to change."""

from __future__ import annotations

import pytest

from sim.commands import main
from tests.scenes import heaving_farm


def one_line(capsys) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    return err


@pytest.mark.parametrize("argv, says", [
    (["run", "--points-per-edge", "1000"], ["6,000,000 surface samples", "5.7 GB", "--points-per-edge"]),
    (["sweep", "--param", "density=1:2:1000", "--param", "tilt=0:10:1000"], ["1,000,000 cases", "limit of 200,000"]),
    (["sweep", "--param", "density=300,500", "--history-every", "1", "--t-end", "1e6"], ["28.8 GB", "--history-every"]),
    (["run", "--scene", "log", "--samples", "3000000"], ["mesh samples must be <= 1e+06"]),
    (["run", "--scene", "storm", "--points-per-edge", "100", "--wave-components", "4096", "--t-end", "1e5"],
     ["20,000,000 steps of 60,000 surface samples in 4,096 wave components", "about 25 h", "--max-hours"]),
])  # fmt: skip
def test_costly_settings_are_refused_with_their_estimate(argv, says, capsys, tmp_path):
    assert main([*argv, "--out", str(tmp_path / "x")]) == 2
    err = one_line(capsys)
    for text in says:
        assert text in err


def test_the_limit_follows_the_memory_this_machine_has(monkeypatch, capsys):
    monkeypatch.setattr("sim.limits.available_bytes", lambda: 100e6)  # a small machine: 100 MB free
    assert main(["run", "--points-per-edge", "200", "--t-end", "0.01"]) == 2  # 240 000 samples, about 228 MB
    err = one_line(capsys)
    assert "228 MB" in err and "100 MB available" in err and "--points-per-edge" in err
    assert main(["run", "--points-per-edge", "50", "--t-end", "0.01"]) == 0


def test_a_long_decay_record_is_checked_against_memory(monkeypatch, capsys):
    monkeypatch.setattr("sim.limits.available_bytes", lambda: 100e6)
    from studies.decay import DecayArgs, decay

    with pytest.raises(Exception, match="a record of 20,000,001 steps needs about 320 MB"):
        decay(DecayArgs(scene="damped", duration=1e5))


def test_a_farm_past_the_memory_is_refused_before_a_device_is_built(monkeypatch, capsys, tmp_path):
    """100 x 100 heaving cubes: 6,000,000 samples (5.7 GB) and the system's matrices over 10,000 degrees of freedom
    (430 B each of n^2: 43 GB), refused in one line naming the farm's rows and columns (it took 10 GB and minutes, silent)."""
    monkeypatch.setattr("sim.limits.available_bytes", lambda: 16e9)
    assert main(["run", "--scene", heaving_farm(tmp_path, 100), "--t-end", "0.1"]) == 2
    err = one_line(capsys)
    assert "6,000,000 surface samples and 10,000 degrees of freedom" in err and "48.7 GB" in err
    assert "[farm] rows and columns (100 x 100 devices)" in err


def test_a_run_past_its_hours_is_refused_and_runs_when_asked(capsys, tmp_path):
    """A farm of 20 x 20 (400 degrees of freedom: about 1.3 s a step on one core) for 1000 s of 0.01 s steps: about 35 h,
    refused naming --max-hours before any device is built; under a larger budget the same scene is let through to its
    set-up (cut short here by --max-steps, which is checked first)."""
    scene = heaving_farm(tmp_path, 20)
    assert main(["run", "--scene", scene, "--t-end", "1000", "--dt", "0.01"]) == 2
    err = one_line(capsys)
    assert "100,000 steps of 240,000 surface samples and 400 degrees of freedom" in err and "more than --max-hours 24" in err
    assert main(["run", "--scene", scene, "--t-end", "1000", "--dt", "0.01", "--max-hours", "100", "--max-steps", "10"]) == 2
    assert "more than --max-steps 10" in one_line(capsys)
    assert main(["run", "--max-hours", "0"]) == 2 and "--max-hours must be > 0" in one_line(capsys)


def test_a_long_set_up_is_announced_with_its_estimate_before_it_starts(capsys):
    """540,000 samples on the cube (about 3.8 s to set up on one core, 513 MB): the note comes first, then the run."""
    assert main(["run", "--points-per-edge", "300", "--t-end", "0"]) == 0
    out = capsys.readouterr()
    first = out.err.splitlines()[0]
    assert first.startswith("floatsim: note: 540,000 surface samples: about 4 s to set up and 513 MB of memory")
    assert "with 540000 samples" in out.out


def test_a_sea_of_many_components_is_counted_in_the_set_up_it_announces(capsys):
    """The first frame evaluates every wave component at every sample (60 ns each, measured): 60,000 samples in 1024
    components are about 4 s, said before they start (the 64 components of the storm preset add 0.2 s, not said)."""
    assert main(["run", "--scene", "storm", "--points-per-edge", "100", "--wave-components", "1024", "--t-end", "0"]) == 0
    first = capsys.readouterr().err.splitlines()[0]
    assert first.startswith("floatsim: note: 60,000 surface samples in 1,024 wave components: about 4 s to set up"), first
    assert main(["run", "--scene", "storm", "--points-per-edge", "100", "--t-end", "0"]) == 0
    assert "to set up" not in capsys.readouterr().err

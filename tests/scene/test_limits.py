"""Settings whose cost grows are checked against stated limits before anything is allocated; the
message names the estimated memory and the flag to change."""

from __future__ import annotations

import pytest

from sim.commands import main


def one_line(capsys) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    return err


@pytest.mark.parametrize("argv, says", [
    (["run", "--points-per-edge", "1000"], ["6,000,000 surface samples", "2.7 GB", "--points-per-edge"]),
    (["sweep", "--param", "density=1:2:1000", "--param", "tilt=0:10:1000"], ["1,000,000 cases", "limit of 200,000"]),
    (["sweep", "--param", "density=300,500", "--history-every", "1", "--t-end", "1e6"], ["28.8 GB", "--history-every"]),
    (["run", "--scene", "log", "--samples", "3000000"], ["mesh samples must be <= 1e+06"]),
])  # fmt: skip
def test_costly_settings_are_refused_with_their_estimate(argv, says, capsys, tmp_path):
    assert main([*argv, "--out", str(tmp_path / "x")]) == 2
    err = one_line(capsys)
    for text in says:
        assert text in err


def test_the_limit_follows_the_memory_this_machine_has(monkeypatch, capsys):
    monkeypatch.setattr("sim.limits.available_bytes", lambda: 100e6)  # a small machine: 100 MB free
    assert main(["run", "--points-per-edge", "200", "--t-end", "0.01"]) == 2  # 240 000 samples, about 108 MB
    err = one_line(capsys)
    assert "108 MB" in err and "100 MB available" in err and "--points-per-edge" in err
    assert main(["run", "--points-per-edge", "50", "--t-end", "0.01"]) == 0


def test_a_long_decay_record_is_checked_against_memory(monkeypatch, capsys):
    monkeypatch.setattr("sim.limits.available_bytes", lambda: 100e6)
    from studies.decay import DecayArgs, decay

    with pytest.raises(Exception, match="a record of 20,000,001 steps needs about 320 MB"):
        decay(DecayArgs(scene="damped", duration=1e5))

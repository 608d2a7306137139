"""``auvsim dataset --workers N`` above the CPUs the process may use: capped to them, with a
note on the console; within them, as given."""

from __future__ import annotations

import pytest

from sim.cli import dataset_cmd, main


@pytest.mark.parametrize(("asked", "cpus", "used"), [(64, 2, 2), (3, 1, 1), (2, 2, 2), (None, 2, None)])
def test_workers_above_the_usable_cpus_are_capped_with_a_note(asked, cpus, used, monkeypatch, capsys, tmp_path):
    import sim.dataset.generate as gen

    got = {}

    def fake_generate(out, n, **kw):
        got.update(kw)
        return tmp_path / "annotations.json"

    monkeypatch.setattr(gen, "generate_dataset", fake_generate)
    monkeypatch.setattr(dataset_cmd, "usable_cpus", lambda: cpus)
    argv = ["dataset", "--n", "4", "--out", str(tmp_path / "ds")] + ([] if asked is None else ["--workers", str(asked)])
    assert main(argv) == 0
    err = capsys.readouterr().err
    assert got["workers"] == used
    if asked is not None and asked > cpus:
        assert f"--workers {asked}: more than the CPUs this process may use ({cpus}); using {cpus}" in err
    else:
        assert "--workers" not in err


def test_usable_cpus_follows_the_affinity_mask_not_the_machine():
    """Pinned to one CPU (``taskset -c 0``), one worker, whatever ``os.cpu_count()`` says."""
    import os

    if not hasattr(os, "sched_getaffinity"):
        pytest.skip("no affinity mask here")
    before = os.sched_getaffinity(0)
    try:
        os.sched_setaffinity(0, {min(before)})
        assert dataset_cmd.usable_cpus() == 1
    finally:
        os.sched_setaffinity(0, before)
    assert dataset_cmd.usable_cpus() == len(before)

"""``--overwrite`` of an earlier run replaces what that run wrote (its marker lists it), study
files included, and nothing a user added."""

from __future__ import annotations

import pytest

from sim.outputs.run_dir import OutputDirError, StagedOutput, check_output_dir


def _earlier_run(out, names):
    staged = StagedOutput(check_output_dir(out, kind="run"), "run")
    with staged as tmp:
        for n in names:
            (tmp / n).write_text("x")
        staged.commit()


def test_files_of_a_study_the_run_wrote_may_be_overwritten(tmp_path):
    out = tmp_path / "run"
    _earlier_run(out, ["metrics.json", "mcm.json", "gospa.png", "scenario.yaml"])
    assert check_output_dir(out, kind="run", overwrite=True) == out.resolve()


def test_a_file_the_user_added_is_not(tmp_path):
    out = tmp_path / "run"
    _earlier_run(out, ["metrics.json", "mcm.json"])
    (out / "my_notes.txt").write_text("mine")
    with pytest.raises(OutputDirError, match="my_notes.txt"):
        check_output_dir(out, kind="run", overwrite=True)
    assert (out / "my_notes.txt").read_text() == "mine"

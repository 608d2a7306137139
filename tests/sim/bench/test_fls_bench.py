"""auvsim bench fls: the frames timed without the ground truth are the frames timed with it."""

from scenarios import load_scenario
from sim.bench import fls as fls_bench


def test_fls_bench_times_both_passes_on_the_same_frames():
    r = fls_bench.run(load_scenario("cssn_lawnmower"), n_frames=3)
    assert r["n_frames"] == 3 and r["visible_objects"] > 0
    bare = r["no_truth"]
    assert bare["identical_frames"] is True
    assert bare["frames_per_s"] > 0 and bare["cpu_ms_per_frame"] > 0

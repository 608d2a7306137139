"""auvsim bench fls: the frames timed without the ground truth are the frames timed with it."""

from scenarios import load_scenario
from sim.bench import fls as fls_bench


def test_fls_bench_times_both_passes_on_the_same_frames():
    r = fls_bench.run(load_scenario("cssn_lawnmower"), n_frames=3)
    assert r["n_frames"] == 3 and r["visible_objects"] > 0
    bare = r["no_truth"]
    assert bare["identical_frames"] is True
    assert bare["frames_per_s"] > 0 and bare["cpu_ms_per_frame"] > 0


def test_fls_bench_times_the_renderer_before_in_the_same_run():
    from sim.sensors import embree_scene

    r = fls_bench.run(load_scenario("cssn_lawnmower"), n_frames=2, without_truth=False)
    base = r["baseline"]
    assert base["before"]["speedup_cpu"] == 1.0
    assert ("embree" in base) == embree_scene.available()
    for v in base.values():
        assert v["cpu_ms_per_frame"] > 0 and v["cpu_frames_per_s"] > 0
        assert abs(v["speedup_cpu"] - base["before"]["cpu_ms_per_frame"] / v["cpu_ms_per_frame"]) < 0.01 * v["speedup_cpu"]
    # a scenario already on the stream speckle has nothing to compare against
    stream = load_scenario("cssn_lawnmower", ["sensors.fls.speckle_generator=stream"])
    assert "baseline" not in fls_bench.run(stream, n_frames=1, without_truth=False)

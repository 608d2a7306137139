"""GOSPA (alpha 2) against Stone Soup's GOSPAMetric, the library oracle, on 200 random cases."""

from __future__ import annotations

import numpy as np
import pytest

from sim.evaluation.world_model_score import gospa

stonesoup = pytest.importorskip("stonesoup")


def test_gospa_equals_stone_soup_on_random_cases():
    from stonesoup.measures import Euclidean
    from stonesoup.metricgenerator.ospametric import GOSPAMetric
    from stonesoup.types.state import State

    rng = np.random.default_rng(21)
    for case in range(200):
        c, p = (50.0, 1.0) if case % 2 == 0 else (float(rng.uniform(2, 30)), float(rng.choice([1.0, 2.0])))
        est = rng.uniform(0, 100, (int(rng.integers(0, 7)), 2))
        tru = rng.uniform(0, 100, (int(rng.integers(0, 7)), 2))
        metric = GOSPAMetric(c=c, p=p, measure=Euclidean(mapping=(0, 1)))
        ours = gospa(est, tru, c=c, p=p)
        if len(est) == 0 and len(tru) == 0:
            assert ours == 0.0
            continue
        oracle = metric.compute_gospa_metric([State(np.c_[x]) for x in est], [State(np.c_[y]) for y in tru])[0].value
        assert ours == pytest.approx(oracle["distance"], rel=1e-9, abs=1e-9)

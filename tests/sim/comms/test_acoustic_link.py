"""Acoustic modem link: exact timing on static geometry (duration, travel, queueing, half
duplex), loss rates against the configured curve, collisions, multipath, seeding, statistics."""

from __future__ import annotations

import math

import numpy as np
import pytest
from pydantic import ValidationError

from scenarios.config.comms import AcousticLinkConfig
from sim.comms import AcousticLink

C = 1500.0
RATE = 1000.0
OVERHEAD = 16
EXACT = dict(bit_rate_bps=RATE, overhead_bytes=OVERHEAD, loss_near=0.0, loss_far=0.0, noise_loss_per_mps=0.0,
             multipath_prob=0.0, sound_speed_mps=C)
A, B = np.zeros(3), np.array([300.0, 400.0, 0.0])  # 500 m apart


def _dur(n_bytes):
    return (n_bytes + OVERHEAD) * 8 / RATE


def _link(nodes=("a", "b"), seed=0, **kw):
    return AcousticLink(AcousticLinkConfig(**(EXACT | kw)), list(nodes), np.random.default_rng(seed))


def _run(link, positions, t_end, dt=0.05, t0=0.0):
    """Advance in ticks of ``dt`` to ``t_end`` collecting what is delivered, with the tick it came in."""
    got = []
    for t in np.arange(t0, t_end + 1e-9, dt):
        link.advance(float(t), positions)
        got += [(float(t), p) for p in link.delivered(float(t))]
    return got


def test_one_message_arrives_after_duration_plus_travel_exactly():
    link = _link()
    pos = {"a": A, "b": B}  # 500 m apart
    link.advance(0.0, pos)
    pid = link.send(1.0, "a", "b", bytes(40))
    got = _run(link, pos, 3.0)
    assert len(got) == 1
    t_tick, p = got[0]
    expected = 1.0 + 500.0 / C + _dur(40)
    assert p.id == pid and p.outcome == "delivered" and p.payload == bytes(40)
    assert p.t_arrival_s == pytest.approx(expected, abs=1e-12) and p.range_m == pytest.approx(500.0)
    assert p.latency_s == pytest.approx(500.0 / C + _dur(40), abs=1e-12)
    assert t_tick - 0.05 < expected <= t_tick  # handed over at the first tick after it arrived
    # one coarse step settles the same times
    coarse = _link()
    coarse.advance(0.0, pos)
    coarse.send(1.0, "a", "b", bytes(40))
    coarse.advance(10.0, pos)
    assert coarse.delivered(10.0)[0].t_arrival_s == pytest.approx(expected, abs=1e-12)


def test_queue_of_messages_goes_back_to_back():
    link = _link()
    pos = {"a": A, "b": B}
    link.advance(0.0, pos)
    sizes = [10, 50, 1, 64]
    for n in sizes:
        link.send(0.0, "a", "b", bytes(n))
    got = [p for _, p in _run(link, pos, 5.0)]
    starts = np.concatenate([[0.0], np.cumsum([_dur(n) for n in sizes])[:-1]])
    assert [p.t_tx_start_s for p in got] == pytest.approx(starts.tolist(), abs=1e-12)
    assert [p.t_arrival_s for p in got] == pytest.approx((starts + [_dur(n) for n in sizes] + 500 / C).tolist(),
                                                          abs=1e-12)
    assert [len(p.payload) for p in got] == sizes


def test_half_duplex_receiver_waits_until_the_arrival_ends():
    """b wants to send while a's packet is arriving: it starts when the arrival ends."""
    link = _link()
    pos = {"a": A, "b": B}
    tau, d = 500 / C, _dur(40)
    link.advance(0.0, pos)
    link.send(0.0, "a", "b", bytes(40))
    link.advance(tau + d / 2, pos)
    link.send(tau + d / 2, "b", "a", bytes(8))
    got = {p.src: p for _, p in _run(link, pos, 4.0, t0=tau + d / 2)}
    assert got["a"].t_arrival_s == pytest.approx(tau + d, abs=1e-12)
    assert got["b"].t_tx_start_s == pytest.approx(tau + d, abs=1e-12)
    assert got["b"].t_arrival_s == pytest.approx(tau + d + _dur(8) + tau, abs=1e-12)


def _back_to_back_case(dt, third_node):
    """a sends two 32-byte packets to b at 1.3 s, 300 m away; b wants to send at 1.6 s,
    during the first arrival. Ticks of ``dt``, sends before each tick's advance (as the
    mission does). With ``third_node``, c (1500 m from b, 1530 m from a) sends to a at 1.9 s,
    after the first arrival at b ended and during the second: an event between b's wish and
    its start."""
    nodes = ("a", "b", "c") if third_node else ("a", "b")
    pos = {"a": A, "b": np.array([300.0, 0.0, 0.0]), "c": np.array([300.0, 1500.0, 0.0])}
    pos = {n: pos[n] for n in nodes}
    link = _link(nodes=nodes)
    sends = {1.3: [("a", "b", 32), ("a", "b", 32)], 1.6: [("b", "a", 8)]}
    if third_node:
        sends[1.9] = [("c", "a", 8)]
    for k in range(int(round(6.0 / dt)) + 1):
        t = round(k * dt, 9)
        for src, dst, n in sends.get(t, []):
            link.send(t, src, dst, bytes(n))
        link.advance(t, pos)
    return link, pos


@pytest.mark.parametrize("third_node", [False, True])
@pytest.mark.parametrize("dt", [0.1, 0.05])
def test_receiver_waits_for_back_to_back_arrivals_and_hears_both(dt, third_node):
    """A start is never in the settled past: b waits for the end of both of a's packets."""
    link, pos = _back_to_back_case(dt, third_node)
    tau_ab = math.dist(pos["a"], pos["b"]) / C  # 0.2 s
    arrival_ends = [1.3 + tau_ab + _dur(32), 1.3 + tau_ab + 2 * _dur(32)]  # 1.884, 2.268 s
    got = {(p.src, p.t_arrival_s): p for p in link.finished()}
    from_a = sorted((p for p in link.finished() if p.src == "a"), key=lambda p: p.t_arrival_s)
    assert [p.outcome for p in from_a] == ["delivered", "delivered"]
    assert [p.t_arrival_s for p in from_a] == pytest.approx(arrival_ends, abs=1e-12)
    (b_pkt,) = [p for p in got.values() if p.src == "b"]
    assert b_pkt.t_tx_start_s == pytest.approx(arrival_ends[-1], abs=1e-12)  # 2.268 s, not 1.6 s
    assert b_pkt.outcome == "delivered"
    assert b_pkt.t_arrival_s == pytest.approx(arrival_ends[-1] + _dur(8) + tau_ab, abs=1e-12)
    s = link.stats()
    assert (s.lost_half_duplex, s.lost_collision, s.pending) == (0, 0, 0)


def test_half_duplex_transmitting_node_is_deaf():
    """b starts first; a starts before b's signal reaches it, so each transmits while the
    other's packet arrives: both lost, cause half_duplex."""
    link = _link()
    pos = {"a": A, "b": B}
    tau = 500 / C  # 0.333 s; b's packet lasts 0.64 s > 1.5 tau, so it still sends when a's arrives
    link.advance(0.0, pos)
    link.send(0.0, "b", "a", bytes(64))
    link.advance(tau / 2, pos)
    link.send(tau / 2, "a", "b", bytes(40))
    link.advance(5.0, pos)
    assert link.delivered(5.0) == []
    assert sorted(p.outcome for p in link.finished()) == ["half_duplex", "half_duplex"]
    s = link.stats()
    assert (s.sent, s.delivered, s.lost_half_duplex, s.pending) == (2, 0, 2, 0)


def test_overlapping_arrivals_collide_at_the_receiver():
    link = _link(nodes=("a", "b", "c"))
    pos = {"a": A, "b": B, "c": B + np.array([0.0, 0.0, 500.0])}  # both 500 m from b
    link.advance(0.0, pos)
    link.send(0.0, "a", "b", bytes(20))
    link.send(0.0, "c", "b", bytes(20))
    link.advance(5.0, pos)
    assert [p.outcome for p in link.finished()] == ["collision", "collision"]
    # spaced by more than a packet, both arrive (c hears a first and waits for it to pass)
    link2 = _link(nodes=("a", "b", "c"))
    link2.advance(0.0, pos)
    link2.send(0.0, "a", "b", bytes(20))
    link2.send(0.0 + _dur(20) + 0.01, "c", "b", bytes(20))
    link2.advance(5.0, pos)
    assert [p.outcome for p in link2.finished()] == ["delivered", "delivered"]


def _expected_delivery(r, v_src, v_dst, near, far, r50, width, k_noise):
    """The documented curve written out: logistic range loss times each end's noise term."""
    p_range = near + (far - near) / (1.0 + math.exp(-(r - r50) / width))
    return (1 - p_range) * (1 - min(k_noise * v_src, 1)) * (1 - min(k_noise * v_dst, 1))


@pytest.mark.parametrize(("range_m", "speed_src", "speed_dst"), [(500.0, 0.0, 0.0), (1000.0, 0.5, 0.0),
                                                                 (1400.0, 0.5, 1.0)])
def test_loss_rate_over_10000_packets_within_binomial_band(range_m, speed_src, speed_dst):
    n = 10_000
    params = dict(loss_near=0.02, loss_far=1.0, loss_range50_m=1000.0, loss_range_width_m=200.0,
                  noise_loss_per_mps=0.1)
    link = _link(seed=int(range_m), queue_limit=n, **params)
    pos = {"a": A, "b": np.array([range_m, 0.0, 0.0])}
    link.advance(0.0, pos, speeds_mps={"a": speed_src, "b": speed_dst})
    for _ in range(n):
        link.send(0.0, "a", "b", bytes(1))
    link.advance(n * _dur(1) + 10.0, pos, speeds_mps={"a": speed_src, "b": speed_dst})
    s = link.stats()
    assert s.sent == n and s.pending == 0 and s.lost == s.lost_channel
    p = _expected_delivery(range_m, speed_src, speed_dst, 0.02, 1.0, 1000.0, 200.0, 0.1)
    band = 4.0 * math.sqrt(n * p * (1 - p))
    assert abs(s.delivered - n * p) <= band, (s.delivered, n * p, band)


def test_speed_from_positions_feeds_the_noise_term():
    """Without explicit speeds, a node moving 1 m/s between advances loses k_noise of its packets."""
    n = 4000
    link = _link(queue_limit=n, noise_loss_per_mps=0.3)
    link.advance(0.0, {"a": A, "b": B})
    for _ in range(n):
        link.send(0.0, "a", "b", bytes(1))
    t_end = n * _dur(1) + 5.0
    link.advance(t_end, {"a": A + [t_end, 0, 0], "b": B})  # a moved at 1 m/s
    delivered = link.stats().delivered
    assert abs(delivered - 0.7 * n) <= 4 * math.sqrt(n * 0.21)


def test_moving_receiver_range_at_transmission_start():
    link = _link()
    link.advance(0.0, {"a": A, "b": np.array([100.0, 0.0, 0.0])})
    link.send(5.0, "a", "b", bytes(4))
    link.advance(10.0, {"a": A, "b": np.array([200.0, 0.0, 0.0])})  # b at 150 m at t = 5 s
    (p,) = link.delivered(10.0)
    assert p.range_m == pytest.approx(150.0)
    assert p.t_arrival_s == pytest.approx(5.0 + _dur(4) + 150.0 / C, abs=1e-12)


def test_multipath_adds_a_bounded_uniform_delay():
    n = 3000
    link = _link(queue_limit=n, multipath_prob=1.0, multipath_max_delay_s=0.05)
    pos = {"a": A, "b": B}
    link.advance(0.0, pos)
    for _ in range(n):
        link.send(0.0, "a", "b", bytes(1))
    t_end = n * _dur(1) + 10.0
    link.advance(t_end, pos)
    got = link.delivered(t_end)
    assert len(got) == n and all(p.multipath for p in got)
    assert all(type(p.t_arrival_s) is float for p in got)
    extra = np.array([p.t_arrival_s - p.t_tx_start_s - _dur(1) - 500 / C for p in got])
    assert extra.min() >= 0.0 and extra.max() <= 0.05
    assert abs(extra.mean() - 0.025) <= 4 * 0.05 / math.sqrt(12 * n)


def test_same_seed_same_run_and_statistics():
    def run(seed):
        link = _link(seed=seed, loss_near=0.3, loss_far=0.3, multipath_prob=0.2, queue_limit=500)
        pos = {"a": A, "b": B}
        link.advance(0.0, pos)
        for k in range(200):
            link.send(0.0, "a" if k % 3 else "b", "b" if k % 3 else "a", bytes(1 + k % 30))
        link.advance(60.0, pos)
        return link

    r1, r2, r3 = run(7), run(7), run(8)
    assert [(p.id, p.outcome, p.t_arrival_s) for p in r1.finished()] == \
        [(p.id, p.outcome, p.t_arrival_s) for p in r2.finished()]
    assert [p.outcome for p in r1.finished()] != [p.outcome for p in r3.finished()]
    s = r1.stats()
    lat = np.array([p.latency_s for p in r1.finished() if p.outcome == "delivered"])
    assert s.sent == 200 == s.delivered + s.lost + s.pending
    assert s.mean_latency_s == pytest.approx(lat.mean()) and s.p95_latency_s == pytest.approx(np.percentile(lat, 95))
    assert r1.stats(src="a").sent + r1.stats(src="b").sent == 200


def test_queue_full_drops_and_bad_calls_raise():
    link = _link(queue_limit=2)
    pos = {"a": A, "b": B}
    link.advance(0.0, pos)
    ids = [link.send(0.0, "a", "b", b"x") for _ in range(3)]
    assert ids == [0, 1, 2] and link.finished()[0].outcome == "queue_full"
    with pytest.raises(ValueError, match="payload of 65 bytes"):
        link.send(0.0, "a", "b", bytes(65))
    with pytest.raises(ValueError, match="unknown node 'z'"):
        link.send(0.0, "a", "z", b"x")
    with pytest.raises(ValueError, match="cannot send to itself"):
        link.send(0.0, "a", "a", b"x")
    link.advance(1.0, pos)
    with pytest.raises(ValueError, match="before the last advance"):
        link.send(0.5, "a", "b", b"x")
    with pytest.raises(ValueError, match="needs advance"):
        link.delivered(2.0)
    with pytest.raises(ValueError, match="no position for node 'b'"):
        link.advance(2.0, {"a": A})
    with pytest.raises(ValueError, match=r"position of 'b' must be a finite \(3,\) NED vector"):
        link.advance(2.0, {"a": A, "b": [np.nan, 0.0, 0.0]})
    with pytest.raises(ValueError, match=r"position of 'a' must be a finite \(3,\) NED vector"):
        link.advance(2.0, {"a": [1.0, 2.0], "b": B})
    with pytest.raises(ValueError, match="distinct node names"):
        _link(nodes=("a", "a"))


def test_config_limits_and_scenario_default():
    with pytest.raises(ValidationError, match="bit_rate_bps"):
        AcousticLinkConfig(bit_rate_bps=40.0)
    with pytest.raises(ValidationError, match="bit_rate_bps"):
        AcousticLinkConfig(bit_rate_bps=25_000.0)
    with pytest.raises(ValidationError, match="multipath_prob"):
        AcousticLinkConfig(multipath_prob=1.2)
    with pytest.raises(ValidationError, match="loss_far"):
        AcousticLinkConfig(loss_near=0.5, loss_far=0.2)
    cfg = AcousticLinkConfig()
    assert cfg.packet_duration_s(32) == pytest.approx((32 + 16) * 8 / 1000.0)
    assert cfg.delivery_prob(3500.0) == pytest.approx(0.49)  # half-way between 2 % and 100 % loss
    from scenarios.load import load_scenario

    sc = load_scenario("cssn_lawnmower")
    assert sc.comms.acoustic.enabled is False
    # the link needs its surface vehicle (comms.surface.vehicle): the sea trial has it
    on = load_scenario("cssn_sea_trial", ["comms.acoustic.bit_rate_bps=4000"])
    assert on.comms.acoustic.bit_rate_bps == 4000.0


def test_bad_link_setting_is_one_error_naming_the_key():
    from scenarios.load import ScenarioError, load_scenario

    with pytest.raises(ScenarioError, match=r"comms\.acoustic\.bit_rate_bps .*greater than or equal to 50"):
        load_scenario("cssn_lawnmower", ["comms.acoustic.bit_rate_bps=10"])

"""Progress: bars on a terminal, one line per phase and per finished run in a log."""

from __future__ import annotations

import io
import itertools
import sys

from sigmapi.progress import HEARTBEAT_S, Heartbeat, Lines, counter, each, progress_callback


class _Model:
    def __init__(self) -> None:
        self.t_, self.sigma_ = 0, 1.0


def test_a_log_gets_one_line_per_phase_and_per_finished_run(capsys):
    # capsys: stderr is not a terminal, as in `sigmapi reproduce > log 2>&1`
    callback, bar = progress_callback(3000, "train tiny seed 0")
    model = _Model()
    with bar:
        for t in (1000, 2000, 3000):
            model.t_ = t
            callback(model)
    step, bar = counter(30, "reach", "episodes")
    with bar:
        for phase in ("map", "map", "retina"):
            step(10, phase)
    assert list(each([1, 2], "figures")) == [1, 2]
    lines = capsys.readouterr().err.splitlines()
    assert lines[0].startswith("train tiny seed 0: 3,000 of 3,000 it in ")
    assert lines[1:4] == ["reach: map", "reach: retina", lines[3]]
    assert lines[3].startswith("reach: 30 of 30 episodes in ")
    assert lines[4].startswith("figures: 2 of 2 in ") and len(lines) == 5
    callback, bar = progress_callback(10, "quiet", disable=True)
    with bar:
        callback(model)
    assert capsys.readouterr().err == ""


class _Clock:
    def __init__(self) -> None:
        self.now = 1000.0

    def __call__(self) -> float:
        return self.now


class _Stamped(io.StringIO):
    """stderr that notes the (fake) time of each line written."""

    def __init__(self, clock: _Clock) -> None:
        super().__init__()
        self.clock, self.stamps = clock, []

    def write(self, text: str) -> int:
        self.stamps += [self.clock()] * text.count("\n")
        return super().write(text)


def test_a_log_hears_from_an_open_bar_at_least_every_30_s_with_an_estimate(monkeypatch):
    clock = _Clock()
    err = _Stamped(clock)
    monkeypatch.setattr(sys, "stderr", err)
    heart = Heartbeat(period=HEARTBEAT_S, clock=clock)
    start = clock()
    with Lines(600, "work", "ep", heart=heart) as bar:
        for second in range(1, 601):  # ten minutes, the first two without anything done
            clock.now += 1.0
            if second > 120 and second % 2 == 0:
                bar.update(2)
            if second == 300:
                bar.set_postfix_str("second half")
            heart.beat()  # what the heartbeat's thread does each second
    lines = err.getvalue().splitlines()
    stamps = [start, *err.stamps, clock()]
    assert max(b - a for a, b in itertools.pairwise(stamps)) <= 30
    assert HEARTBEAT_S <= 30 and len(lines) >= 600 / 30
    assert lines[0] == (
        "work: 0 of 600 ep after 20 s, 600 left, no estimate before the first is done"
    )
    # the estimate is the measured throughput: 460 in 580 s, 140 left at 0.79/s
    assert lines[-3] == (
        "work: 460 of 600 ep after 9 min 40 s, 140 left, about 2 min 57 s more (0.79 ep/s); "
        "second half"
    )
    assert "work: second half" in lines and lines[-1] == "work: 480 of 600 ep in 600.0 s (0.8 ep/s)"
    # a bar that writes lines of its own more often than the period gets no status lines
    err.truncate(0), err.seek(0)
    with Lines(100, "busy", "ep", heart=heart) as bar:
        for i in range(100):
            clock.now += 15.0
            bar.set_postfix_str(f"phase {i}")
            bar.update(1)
            heart.beat()
    assert "left" not in err.getvalue()

"""Independent solves over the cores (``magtact._parallel.fork_map``) give what one process
gives, and the sensor problem's reduction leaves out only chip options that cannot win."""

import os
import warnings

import pytest

from magtact import _parallel


def test_fork_map_equals_the_loop_and_takes_what_does_not_pickle():
    lock = __import__("threading").Lock()  # unpicklable: the items travel as indices
    fn = lambda x: (x * x, lock is not None)  # noqa: E731
    items = list(range(7))
    assert _parallel.fork_map(fn, items, workers=2) == [fn(x) for x in items]
    assert _parallel.fork_map(fn, [], workers=2) == []


def test_fork_map_hands_out_the_first_items_first_and_returns_the_items_order():
    import time

    items = [3, 0, 2, 1]
    assert _parallel.fork_map(lambda x: x * x, items, workers=2, first=lambda x: -x) == \
        [9, 0, 4, 1]
    # each job lasts 0.5 s: the two workers start 3 and 2, then 1 and 0
    started = _parallel.fork_map(lambda x: (time.monotonic(), time.sleep(0.5))[0], items,
                                 workers=2, first=lambda x: -x)
    assert max(started[0], started[2]) < min(started[1], started[3])


def test_fork_map_runs_in_other_processes_where_it_can():
    pids = set(_parallel.fork_map(lambda _: os.getpid(), range(4), workers=2))
    if _parallel._can_fork(2):
        assert os.getpid() not in pids
    else:
        assert pids == {os.getpid()}


def test_fork_map_gives_the_workers_warnings_again_in_order():
    def fn(x):
        warnings.warn(f"item {x}", UserWarning, stacklevel=1)
        return x

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert _parallel.fork_map(fn, [1, 2, 3], workers=2) == [1, 2, 3]
    assert [str(w.message) for w in caught] == ["item 1", "item 2", "item 3"]


def test_fork_map_raises_a_workers_exception_itself():
    class Odd(ValueError):
        def __init__(self, x):  # an exception that does not unpickle
            super().__init__(f"odd item {x}")

    def fn(x):
        if x % 2:
            raise Odd(x)
        return x

    with pytest.raises(Odd, match="odd item 1"):
        _parallel.fork_map(fn, [0, 1, 2], workers=2)


def test_fork_map_computes_here_without_cores(monkeypatch):
    monkeypatch.setattr(_parallel, "cores", lambda: 1)
    assert _parallel.fork_map(lambda _: os.getpid(), range(3)) == [os.getpid()] * 3


def test_the_reduction_without_dominated_chip_options_is_the_same(monkeypatch):
    """Every chip option is compared where none is left out: the same design, to the bit."""
    import magtact
    from magtact.optimise import _sensor, force_table, optimise_sensor

    study = magtact.load("magone", design={"magnet_sizes": []})
    models = magtact.models_for(study)[0]
    table = force_table(models, study, 11)
    space_options = _sensor.sensor_space(models, study, table).options
    kept = _sensor._undominated(space_options)
    assert 0 < len(kept) < len(space_options)
    for k, o in enumerate(space_options):  # a left-out option: an earlier one is no worse
        if k not in kept:
            assert any(p.range_x >= o.range_x and p.range_z >= o.range_z
                       and p.noise_x <= o.noise_x and p.noise_z <= o.noise_z
                       for p in space_options[:k])
    fast = optimise_sensor(models, study, table, nsga2=False)
    monkeypatch.setattr(_sensor, "_undominated", lambda o: frozenset(range(len(o))))
    every = optimise_sensor(models, study, table, nsga2=False)
    assert fast.choice == every.choice
    assert fast.per_silicone == every.per_silicone

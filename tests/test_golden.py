"""Every shipped scene flies bit for bit as it did when ``tests/data/golden_positions.json`` was written (see
``tests/golden.py``): 1,000 steps through ``Simulation.run``, its final positions and every frame's."""

import json

import golden
import pytest

RECORD = json.loads(golden.FILE.read_text())


def test_every_shipped_scene_has_a_digest():
    assert sorted(RECORD["scenes"]) == golden.names() and RECORD["steps"] == golden.STEPS


@pytest.mark.parametrize("name", golden.names())
def test_the_flight_is_bit_for_bit_the_recorded_one(name):
    if RECORD["machine"] != golden.machine():
        pytest.skip(f"the digests were made on {RECORD['machine']!r}, this is {golden.machine()!r}")
    assert golden.fly(name) == RECORD["scenes"][name], f"{name} flies differently: python -m tests.golden if meant"

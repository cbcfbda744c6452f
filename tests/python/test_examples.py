"""The Python examples run (examples/python/): the instrument dragged across the organ, with few
frames, writes its force plot and its GIF, and the force it plots is the instrument's push."""
import os
import sys

import numpy as np
import pytest

from conftest import COMM

EXAMPLES = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "examples", "python")


@pytest.fixture
def instrument(monkeypatch):
    pytest.importorskip("matplotlib")
    monkeypatch.syspath_prepend(EXAMPLES)
    import instrument
    return instrument


def test_instrument_example(instrument, tmp_path, monkeypatch):
    if COMM.size > 1:
        pytest.skip("the example runs on one rank (the contact is solved on rank 0)")
    monkeypatch.setattr(sys, "argv", ["instrument.py", "--frames", "4", "--out", str(tmp_path)])
    assert instrument.main() == 0
    png, gif = tmp_path / "instrument_force.png", tmp_path / "instrument.gif"
    assert png.stat().st_size > 5000 and png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert gif.stat().st_size > 5000 and gif.read_bytes()[:6] == b"GIF89a"


def test_instrument_forces(instrument):
    """Pressed deeper, the instrument pushes the organ down harder; dragged, it keeps pushing
    down (it stays 0.1 deep), at the frames and at the haptic calls between them (their
    positions between the frames'). That the haptic call at a frame's position gives the frame's
    force is test_scene.py's test_haptic_forces."""
    if COMM.size > 1:
        pytest.skip("the example runs on one rank")
    import hssbem
    scene = hssbem.Scene(instrument.load_problem(), stress=False)
    offsets = instrument.path(8)  # 2 frames pressing, 6 dragging
    xs, forces, haptic = instrument.run(scene, offsets, lambda k, offset: None)
    assert forces[0][2] < 0 and forces[1][2] < 1.2 * forces[0][2], forces[:2]
    assert np.all(forces[2:, 2] < 0)
    assert len(haptic) == 3 * 6
    for k in range(2, 8):
        for x, f in haptic[3 * (k - 2):3 * (k - 1)]:
            assert xs[k - 1] < x < xs[k] and f[2] < 0, (k, x, f)

"""hssbem.Scene: frames and contact stepped from Python give the command line's frames; the
fields are views of the scene's storage that follow the frames."""
import json

import numpy as np
import pytest

import hssbem
from conftest import COMM, assert_identical, datasets, problem, reference


def test_scene_frames_identical_to_command_line():
    """The cardioid's travelling patch: frame i by its index and by its dict, the command
    line's /frames/<i> (displacement, traction, stress)."""
    ref = reference("cardioid_scene")
    p = problem("cardioid_scene")
    scene = hssbem.Scene(p)
    assert scene.num_frames == 3
    for i in range(3):
        by_index = scene.step(i)
        fields = {k: np.array(v) for k, v in scene.fields.items()}
        by_dict = scene.step(p["frames"][i])
        if COMM.rank != 0:
            continue
        assert by_index["strategy"] and by_dict["seconds"] > 0
        want = datasets(ref, "frames/%d" % i)
        for name in ("displacement", "traction", "stress", "von_mises"):
            assert_identical(fields[name], want[name], "frame %d %s (index)" % (i, name))
            assert np.allclose(scene.fields[name], want[name], rtol=0, atol=1e-9 * np.abs(want[name]).max()), "frame %d %s (dict)" % (i, name)
        assert np.abs(fields["displacement"]).max() > 0.01


def test_fields_are_views_that_follow_the_frames():
    """scene.fields holds views of the scene's storage: the same memory from frame to frame,
    overwritten in place by the next step (no copy)."""
    p = problem("cardioid_scene")
    scene = hssbem.Scene(p, stress=False)
    scene.step(0)
    if COMM.rank != 0:  # the scene runs on rank 0
        assert scene.fields == {}
        scene.step(1)
        return
    u0 = scene.fields["displacement"]
    first = np.array(u0)
    scene.step(1)
    u1 = scene.fields["displacement"]
    assert "stress" not in scene.fields
    assert np.shares_memory(u0, u1) and not u0.flags.owndata
    assert_identical(u0, u1, "the view after the next step")
    assert np.abs(u1 - first).max() > 1e-3


def close(a, b, what, rel=1e-11):
    """a equals b to round-off: the command line computes the frames' columns ahead (it knows
    them), a Scene per step, so the sums run in another order (measured: 1.5e-16 of 0.03)."""
    a, b = np.asarray(a), np.asarray(b)
    scale = np.nanmax(np.abs(b))
    assert a.shape == b.shape and np.array_equal(np.isnan(a), np.isnan(b)), what
    assert np.nanmax(np.abs(a - b)) <= rel * scale, "%s: largest difference %g of %g" % (what, np.nanmax(np.abs(a - b)), scale)


def test_contact_frames_identical_to_command_line():
    """The organ under the instrument: each frame's contact status (identical), pressure, gap,
    forces and displacement (to round-off), as the command line's /frames/<i>."""
    ref = reference("organ_contact")
    p = problem("organ_contact")
    scene = hssbem.Scene(p)
    assert scene.obstacles == ["table", "tool"]
    for i in range(3):
        report = scene.step(i)
        if COMM.rank != 0:
            continue
        assert report["active_vertices"] > 0
        want = datasets(ref, "frames/%d" % i)
        assert_identical(scene.contact["status"], want["contact/status"], "frame %d status" % i)
        close(scene.fields["displacement"], want["displacement"], "frame %d displacement" % i)
        for name in ("pressure", "gap"):
            close(scene.contact[name], want["contact/" + name], "frame %d %s" % (i, name))
        assert scene.contact["forces"].keys() == {"table", "tool"}
        for name, force in scene.contact["forces"].items():
            close(force, want["contact/forces/" + name], "frame %d force of %s" % (i, name))


def test_contact_frames_as_dicts():
    """The same frames given as dicts (obstacles moved only: the base rules' values kept from
    the set-up), and one with a "boundary" of its own that restates a base rule (applied over
    the mesh): the command line's frames, to round-off."""
    ref = reference("organ_contact")
    p = problem("organ_contact")
    scene = hssbem.Scene(p)
    for i in range(3):
        frame = dict(p["frames"][i])
        if i == 2:
            frame["boundary"] = p["boundary"]
        scene.step(frame)
        if COMM.rank != 0:
            continue
        want = datasets(ref, "frames/%d" % i)
        assert_identical(scene.contact["status"], want["contact/status"], "frame %d status" % i)
        close(scene.fields["displacement"], want["displacement"], "frame %d displacement" % i)
        close(scene.contact["pressure"], want["contact/pressure"], "frame %d pressure" % i)
        close(scene.contact["forces"]["tool"], want["contact/forces/tool"], "frame %d force of the tool" % i)


def test_haptic_forces():
    """The haptic call at the last frame's positions gives that frame's forces (the same
    active set, to round-off), and a deeper instrument presses harder (and the table holds
    more)."""
    p = problem("organ_contact")
    scene = hssbem.Scene(p)
    frame = p["frames"][2]
    scene.step(frame)
    offset = np.array(frame["obstacles"]["tool"]["translate"], float)
    same = scene.haptic_forces({"tool": offset})
    deeper = scene.haptic_forces({"tool": {"translate": offset + [0, 0, -0.005]}})
    if COMM.rank != 0:
        return
    force = scene.contact["forces"]["tool"]
    assert force[2] < 0, force  # the instrument presses the organ down
    for name in ("tool", "table"):
        close(same[name], scene.contact["forces"][name], "haptic force of %s at the frame's offsets" % name)
    assert deeper["tool"][2] < 1.05 * force[2] and deeper["table"][2] > 1.05 * scene.contact["forces"]["table"][2]
    with pytest.raises(hssbem.Error):
        scene.haptic_forces({"scalpel": [0, 0, 0]})


def test_scene_errors():
    p = problem("cardioid_scene")
    scene = hssbem.Scene(p)
    for frame, says in [(7, "the problem has 3 frames"), ({"boundary": [{"where": {"region": "nowhere"}, "displacement": [0, 0, 0]}]}, "nowhere"),
                        ({"bondary": []}, "bondary"), ("frame", "expected a dict")]:
        with pytest.raises(hssbem.Error) as e:
            scene.step(frame)
        assert says in str(e.value) and "\n" not in str(e.value), str(e.value)
    scene.step(0)  # still usable
    with pytest.raises(hssbem.Error) as e:
        hssbem.Scene(p, {"bem_mat_type": "h2"})
    assert "h2" in str(e.value)


def test_scene_saved_and_loaded(tmp_path):
    """A scene's precomputation saved by one Scene (hssbem_save) and loaded by the next
    (hssbem_load) gives the frames to the bit (docs/persistence.md); the update strategy is
    forced, since auto's choice follows measured times."""
    path = COMM.bcast(str(tmp_path / "scene.pre"), root=0)
    p = problem("cardioid_scene")
    cold = hssbem.Scene(p, options={"hssbem_save": path, "scene_strategy": "update"}, stress=False)
    warm_frames = []
    cold_frames = []
    for i in range(3):
        cold.step(i)
        cold_frames.append({k: np.array(v) for k, v in cold.fields.items()})
    warm = hssbem.Scene(p, options={"hssbem_load": path, "scene_strategy": "update"}, stress=False)
    for i in range(3):
        warm.step(i)
        warm_frames.append({k: np.array(v) for k, v in warm.fields.items()})
    if COMM.rank != 0:
        return
    assert np.abs(cold_frames[-1]["displacement"]).max() > 0.01  # frames that move: no test by doing nothing
    for i in range(3):
        for name in ("displacement", "traction"):
            assert_identical(warm_frames[i][name], cold_frames[i][name], "frame %d %s after the load" % (i, name))

"""3D snapshots (drystone/postprocess/snapshots.py ``render``): hidden faces drawn right.

A platform and a course of three stones on its back half, seen from slightly above: the
pixel at the centre of every face of a stone that faces the viewer is stone colour, not
the platform's grey (matplotlib's 3D axes, which sort one collection per block, drew the
platform over the course), and the platform in front of the course is platform grey."""
import json

import numpy as np
import pytest

import tolerances as tol
from conftest import assert_figure
from drystone.geometry import blockfile as bf
from drystone.postprocess import snapshots

STONE = (0.5, 0.4, 0.4)  # m, size of each stone
CENTRES = [(-0.6, 0.8, 0.2), (0.0, 0.8, 0.2), (0.6, 0.8, 0.2)]  # m: on the platform's top (z = 0), behind its middle


def scene(folder):
    """A run folder: platform (id 0, 3 m x 3 m x 0.1 m, top at z = 0) and three free stones
    standing on it side by side, at rest over two samples."""
    folder.mkdir()
    blocks = [{"id": 0, "role": "platform", "material": "m", "vertices": bf.box_vertices((0, 0, -0.05), (3, 3, 0.1))}]
    blocks += [{"id": k + 1, "role": "free", "material": "m", "vertices": bf.box_vertices(c, STONE)}
               for k, c in enumerate(CENTRES)]
    (folder / "geometry.json").write_text(json.dumps({"blocks": blocks}))
    (folder / "spec.json").write_text(json.dumps({"gravity": 9.81, "stages": [
        {"type": "gravity", "start": 0.0, "end": 1.0, "params": {"ramp": 0.5}}]}))
    n = len(CENTRES)
    q = np.tile([0.0, 0.0, 0.0, 1.0], (n, 1))
    c = np.array(CENTRES)
    np.savez(folder / "histories.npz", t=np.array([0.0, 1.0]), tilt_deg=np.zeros(2), block_ids=np.arange(1, n + 1),
             pos0=c, quat0=q, pos=np.stack([c, c]), quat=np.stack([q, q]))
    return folder


def visible_face_centres(elev, azim):
    """Centres (m) of the stones' faces that face the viewer, but a face touching a
    neighbour (hidden by it)."""
    toward = snapshots.view_axes(elev, azim)[2]
    half = np.array(STONE) / 2
    out = []
    for k, c in enumerate(CENTRES):
        for axis in range(3):
            for sign in (-1, 1):
                n = np.zeros(3)
                n[axis] = sign
                touching = axis == 0 and 0 <= k + sign < len(CENTRES)
                if n @ toward > 0 and not touching:
                    out.append(np.array(c) + n * half)
    return out


def pixel(fig, ax, point, elev, azim):
    """RGB (0..1) of the drawn figure at a 3D point's projection."""
    x, y = ax.transData.transform(snapshots.project(point, elev, azim)[0][0])
    img = np.asarray(fig.canvas.buffer_rgba())[..., :3] / 255.0
    return img[int(round(img.shape[0] - y)), int(round(x))]


def test_projection_is_matplotlibs_view():
    """``project``: the direction towards the viewer (elev, azim as matplotlib's view_init)
    goes to the screen's centre, nearest; (-sin azim, cos azim, 0) to the right; z up, by
    cos elev."""
    elev, azim = 15.0, -60.0
    e, a = np.radians(elev), np.radians(azim)
    toward = [np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)]
    xy, depth = snapshots.project([toward, [-np.sin(a), np.cos(a), 0], [0, 0, 1]], elev, azim)
    assert xy == pytest.approx(np.array([[0, 0], [1, 0], [0, np.cos(e)]]), abs=tol.EXACT_ABS)
    assert depth == pytest.approx([1, 0, np.sin(e)], abs=tol.EXACT_ABS)


@pytest.mark.parametrize("elev, azim", [(15, -60), (12, -35), (30, -100)])
def test_platform_does_not_hide_the_stones(tmp_path, elev, azim):
    fig = snapshots.figure(scene(tmp_path / "run"), [0.0], elev=elev, azim=azim)
    fig.canvas.draw()
    ax = fig.axes[0]
    for p in visible_face_centres(elev, azim):
        r, g, b = pixel(fig, ax, p, elev, azim)
        assert r - b >= tol.SNAPSHOT_STONE_RED_MINUS_BLUE, f"stone face at {p} drawn {r:.2f}, {g:.2f}, {b:.2f}"
    r, g, b = pixel(fig, ax, [0.0, 0.45, 0.0], elev, azim)  # the platform's top just in front of the course
    assert abs(r - b) < tol.SNAPSHOT_STONE_RED_MINUS_BLUE and r < 0.5, "platform not drawn in front of the course"


def test_render_keeps_its_signature_and_size(tmp_path):
    """The call of the tilt study (drystone/studies/tilt/study.py ``snapshot_figure``):
    a PNG of 4.2 in x 4.2 in per panel at 110 dpi with the stones drawn."""
    run = scene(tmp_path / "run")
    path = snapshots.render(run, [0.0, 1e9], tmp_path / "s.png", world=True, elev=12, azim=-35,
                            titles=["start", "end"], frame_on_first=True)
    assert_figure(path, (8.4, 4.2), dpi=110)

"""Occupancy maps as worlds: tiny hand-made maps for each quirk, and the two real maps.

The real maps are read from ../shared/realdata/maps (or $LFDFUSE_SHARED); those tests skip
cleanly without them.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import shapely
import yaml
from PIL import Image
from scipy import ndimage

from lfdfuse.errors import WorldError
from lfdfuse.world import occupancy
from lfdfuse.world.model import load_world, parse_world
from tests.conftest import SHARED

MAPS = SHARED / "realdata" / "maps"
FREE, WALL, UNKNOWN = 254, 0, 205


def write_map(
    folder: Path,
    pixels: np.ndarray,
    *,
    name: str = "map",
    fmt: str = "pgm",
    **keys: object,
) -> str:
    """Write ``pixels`` (row 0 = top) as an image and a map_server YAML; returns the YAML path."""
    image = f"{name}.{fmt}"
    Image.fromarray(pixels).save(folder / image)
    meta: dict[str, object] = {
        "image": image,
        "resolution": 0.1,
        "origin": [0.0, 0.0, 0.0],
        "negate": 0,
        "occupied_thresh": 0.65,
        "free_thresh": 0.196,
    }
    meta.update(keys)
    path = folder / f"{name}.yaml"
    path.write_text(yaml.safe_dump(meta))
    return str(path)


def room(h: int = 30, w: int = 40) -> np.ndarray:
    """A free room with a one-cell wall all round."""
    px = np.full((h, w), FREE, dtype=np.uint8)
    px[0, :] = px[-1, :] = px[:, 0] = px[:, -1] = WALL
    return px


def random_map(rng: np.random.Generator, h: int = 36, w: int = 44) -> np.ndarray:
    """A room with random wall blobs, specks and unknown patches."""
    px = room(h, w)
    for _ in range(rng.integers(3, 9)):
        r, c = rng.integers(1, h - 1), rng.integers(1, w - 1)
        px[r : r + rng.integers(1, 7), c : c + rng.integers(1, 7)] = rng.choice([WALL, UNKNOWN])
    return px


def box_distance(px: np.ndarray, py: np.ndarray, solid: np.ndarray, res: float) -> np.ndarray:
    """Exact distance (m) from points to the nearest solid cell square (outside the image is solid)."""
    h, w = solid.shape
    padded = np.pad(solid, 1, constant_values=True)
    rows, cols = np.nonzero(padded)
    x0 = (cols - 1) * res
    y0 = (h - (rows - 1) - 1) * res  # bottom edge of the cell
    dx = np.maximum(np.maximum(x0[None, :] - px[:, None], px[:, None] - (x0[None, :] + res)), 0.0)
    dy = np.maximum(np.maximum(y0[None, :] - py[:, None], py[:, None] - (y0[None, :] + res)), 0.0)
    return np.sqrt(dx * dx + dy * dy).min(axis=1)


def free_centres(free: np.ndarray, res: float) -> tuple[np.ndarray, np.ndarray]:
    rows, cols = np.nonzero(free)
    return (cols + 0.5) * res, (free.shape[0] - rows - 0.5) * res


@pytest.mark.parametrize("seed", range(12))
def test_walls_are_the_boundary_of_the_non_free_cells(tmp_path: Path, seed: int) -> None:
    # law: from every free cell the robot can stand in, the nearest wall is where the nearest
    # non-free cell is, up to the simplification tolerance (one cell)
    rng = np.random.default_rng(seed)
    px = random_map(rng)
    try:
        world = load_world(write_map(tmp_path, px))
    except WorldError as exc:
        assert "no free space" in str(exc)
        return
    res = 0.1
    free = px > 205
    labels, _ = ndimage.label(free)
    region = labels == labels[np.nonzero(free)[0][0], np.nonzero(free)[1][0]]
    sx, sy = free_centres(free, res)
    truth = box_distance(sx, sy, ~free, res)
    got = shapely.distance(shapely.points(sx, sy), world.geometry())
    # cells of pockets too narrow for the robot are filled: compare where the robot fits
    fits = truth > 0.25
    assert np.all(np.abs(got[fits] - truth[fits]) <= res + 1e-9)
    assert region.any()


def test_solid_cells_are_behind_walls(tmp_path: Path) -> None:
    # law: a straight line from deep in free space to deep inside a solid blob crosses a wall
    rng = np.random.default_rng(5)
    for _ in range(8):
        px = random_map(rng)
        try:
            world = load_world(write_map(tmp_path, px))
        except WorldError:
            continue
        free = px > 205
        deep_free = ndimage.binary_erosion(free, iterations=2)
        deep_solid = ndimage.binary_erosion(~free, iterations=2, border_value=1)
        fx, fy = free_centres(deep_free, 0.1)
        qx, qy = free_centres(deep_solid, 0.1)
        if len(fx) == 0 or len(qx) == 0:
            continue
        i, j = rng.integers(0, len(fx), 30), rng.integers(0, len(qx), 30)
        lines = shapely.linestrings(
            np.stack([np.column_stack([fx[i], fy[i]]), np.column_stack([qx[j], qy[j]])], 1)
        )
        assert shapely.intersects(lines, world.geometry()).all()


def test_name_start_and_source_reload(tmp_path: Path) -> None:
    path = write_map(tmp_path, room(), name="lab-2")
    world = load_world(path)
    assert world.name == "lab-2"
    again = parse_world(yaml.safe_load(world.source), source=world.source)
    assert np.array_equal(again.segments, world.segments)
    assert again.start == world.start and again.name == world.name
    # the source is a world file in its own right
    (tmp_path / "copy.yaml").write_text(world.source)
    assert np.array_equal(load_world(str(tmp_path / "copy.yaml")).segments, world.segments)


def test_default_start_is_the_widest_point_of_the_largest_region(tmp_path: Path) -> None:
    # a big room and a small room, and a long corridor too narrow for the robot (more cells
    # than the small room): the robot starts in the middle of the big room
    px = np.full((40, 90), WALL, dtype=np.uint8)
    px[2:38, 2:40] = FREE  # big room, 3.6 × 3.8 m
    px[2:14, 45:57] = FREE  # small room
    px[20:24, 45:89] = FREE  # 0.4 m corridor, no place for a 0.25 m radius robot
    world = load_world(write_map(tmp_path, px))
    x, y, theta = world.start
    free = px > 205
    sx, sy = free_centres(free, 0.1)
    clear = box_distance(sx, sy, ~free, 0.1)
    in_big = sx < 4.0
    assert x < 4.0  # the big room (x from 0.2 to 4.0 m)
    assert box_distance(np.array([x]), np.array([y]), ~free, 0.1)[0] >= clear[in_big].max() - 0.1
    assert world.clearance(x, y) > 0.25 and -math.pi <= theta <= math.pi


def test_map_with_room_only_for_something_smaller_is_an_error(tmp_path: Path) -> None:
    px = np.full((20, 60), WALL, dtype=np.uint8)
    px[8:12, 2:58] = FREE  # 0.4 m wide
    with pytest.raises(WorldError, match="no free space"):
        load_world(write_map(tmp_path, px))


def test_negate_reads_the_inverted_image_the_same(tmp_path: Path) -> None:
    px = random_map(np.random.default_rng(1))
    px[px == UNKNOWN] = 100  # negate turns 205 into 50: use a plain mid grey instead
    a = load_world(write_map(tmp_path, px, name="a"))
    b = load_world(write_map(tmp_path, 255 - px, name="b", negate=1))
    assert np.array_equal(a.segments, b.segments) and a.start == b.start


def test_unknown_cells_are_walls_even_with_ros2_free_thresh(tmp_path: Path) -> None:
    # ROS 2's map_saver writes free_thresh 0.25, under which 205 reads as free by the formula;
    # in trinary mode 205 is the saver's unknown and stays unknown
    px = room()
    px[10:20, 15:25] = UNKNOWN
    base = load_world(write_map(tmp_path, px, name="base"))
    ros2 = load_world(write_map(tmp_path, px, name="ros2", free_thresh=0.25))
    assert np.array_equal(base.segments, ros2.segments)
    inside = (2.0, 1.5)  # the middle of the unknown block
    assert base.clearance(*inside) < 0.6  # walls round the block
    # scale mode reads the thresholds literally: the block becomes free floor
    scale = load_world(write_map(tmp_path, px, name="scale", free_thresh=0.25, mode="scale"))
    assert scale.clearance(*inside) > 1.0
    assert len(scale.segments) < len(base.segments)


def test_raw_mode_reads_occupancy_percent(tmp_path: Path) -> None:
    px = np.zeros((30, 40), dtype=np.uint8)  # 0 % = free
    px[0, :] = px[-1, :] = px[:, 0] = px[:, -1] = 100
    px[10:20, 15:25] = 255  # unknown
    raw = load_world(write_map(tmp_path, px, name="raw", mode="raw"))
    trinary = room()
    trinary[10:20, 15:25] = UNKNOWN
    assert np.array_equal(raw.segments, load_world(write_map(tmp_path, trinary, name="t")).segments)


@pytest.mark.parametrize("mode", ["RGB", "RGBA", "LA", "P"])
def test_png_in_any_pixel_mode_reads_like_the_pgm(tmp_path: Path, mode: str) -> None:
    px = random_map(np.random.default_rng(2))
    want = load_world(write_map(tmp_path, px, name="gray"))
    img = Image.fromarray(px).convert(mode)
    img.save(tmp_path / "c.png")
    meta = yaml.safe_load((tmp_path / "gray.yaml").read_text()) | {"image": "c.png"}
    (tmp_path / "c.yaml").write_text(yaml.safe_dump(meta))
    got = load_world(str(tmp_path / "c.yaml"))
    assert np.array_equal(got.segments, want.segments)


def test_origin_and_yaw_move_the_walls_rigidly(tmp_path: Path) -> None:
    px = random_map(np.random.default_rng(3))
    base = load_world(write_map(tmp_path, px, name="base"))
    ox, oy, yaw = -3.2, 7.5, 0.6
    moved = load_world(write_map(tmp_path, px, name="moved", origin=[ox, oy, yaw]))
    c, s = math.cos(yaw), math.sin(yaw)
    pts = base.segments.reshape(-1, 2)
    want = np.column_stack([ox + c * pts[:, 0] - s * pts[:, 1], oy + s * pts[:, 0] + c * pts[:, 1]])
    assert np.allclose(moved.segments.reshape(-1, 2), want, atol=2e-6)
    bx, by, bth = base.start
    assert moved.start[0] == pytest.approx(ox + c * bx - s * by, abs=2e-6)
    assert moved.start[1] == pytest.approx(oy + s * bx + c * by, abs=2e-6)
    assert math.cos(moved.start[2] - bth - yaw) == pytest.approx(1.0)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"colour": 1}, "unknown map key 'colour'"),
        ({"resolution": -0.1}, "'resolution' must be a number"),
        ({"free_thresh": 0.9}, "'free_thresh' .* is above 'occupied_thresh'"),
        ({"mode": "fancy"}, "'mode' must be one of"),
        ({"negate": 2}, "'negate' must be 0 or 1"),
        ({"origin": [0, "x", 0]}, "'origin' must be a number"),
        ({"origin": 5}, "'origin' must be \\[x, y, yaw\\]"),
        ({"image": "nowhere.pgm"}, "map image .*nowhere.pgm not found"),
    ],
)
def test_bad_map_yaml_is_a_one_line_error(tmp_path: Path, change: dict[str, object], message: str) -> None:
    path = write_map(tmp_path, room())
    meta = yaml.safe_load(Path(path).read_text()) | change
    Path(path).write_text(yaml.safe_dump(meta))
    with pytest.raises(WorldError, match=message) as info:
        load_world(path)
    assert "\n" not in str(info.value)


def test_missing_key_and_broken_image_are_errors(tmp_path: Path) -> None:
    path = write_map(tmp_path, room())
    meta = yaml.safe_load(Path(path).read_text())
    del meta["origin"]
    Path(path).write_text(yaml.safe_dump(meta))
    with pytest.raises(WorldError, match="missing key 'origin'"):
        load_world(path)
    path = write_map(tmp_path, room(), name="broken")
    Path(tmp_path / "broken.pgm").write_bytes(b"P5\n40 30\n255\n" + b"\x00" * 10)
    with pytest.raises(WorldError, match="broken.pgm"):
        load_world(path)
    (tmp_path / "text.pgm").write_text("not an image")
    meta["origin"] = [0, 0, 0]
    meta["image"] = "text.pgm"
    Path(path).write_text(yaml.safe_dump(meta))
    with pytest.raises(WorldError, match="cannot read map image"):
        load_world(path)


def test_sizes_are_bounded(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(occupancy, "MAX_CELLS", 1000)
    with pytest.raises(WorldError, match="40×30 cells"):
        load_world(write_map(tmp_path, room()))
    monkeypatch.setattr(occupancy, "MAX_CELLS", 10_000)
    monkeypatch.setattr(occupancy, "MAX_SEGMENTS", 10)
    with pytest.raises(WorldError, match="wall segments"):
        load_world(write_map(tmp_path, random_map(np.random.default_rng(0)), name="busy"))


def test_all_wall_map_is_an_error(tmp_path: Path) -> None:
    with pytest.raises(WorldError, match="no free space"):
        load_world(write_map(tmp_path, np.full((10, 10), WALL, dtype=np.uint8)))


# -- the two real maps -------------------------------------------------------------------------


def _real(name: str) -> Path:
    path = MAPS / f"{name}.yaml"
    if not path.exists():
        pytest.skip("shared real data not present (../shared/realdata or $LFDFUSE_SHARED)")
    return path


@pytest.mark.parametrize("name", ["willow-2010-02-18-0.10", "mac_1st_floor_final"])
def test_real_map_becomes_a_world_of_thousands_of_walls(name: str) -> None:
    path = _real(name)
    meta = yaml.safe_load(path.read_text())
    world = load_world(str(path))
    assert world.name == name
    assert len(world.segments) >= 1000
    # every wall lies inside the image's extent (origin yaw is 0 for both maps)
    img = Image.open(MAPS / meta["image"])
    res, (ox, oy, _) = meta["resolution"], meta["origin"]
    pts = world.segments.reshape(-1, 2)
    assert pts[:, 0].min() >= ox - 1e-6 and pts[:, 0].max() <= ox + img.width * res + 1e-6
    assert pts[:, 1].min() >= oy - 1e-6 and pts[:, 1].max() <= oy + img.height * res + 1e-6
    # the walls are the boundary of the non-free cells, to a cell, where the robot fits
    shade = np.asarray(img, dtype=np.float64)
    free = ((255 - shade) / 255 < meta["free_thresh"]) & (shade != 205)
    rng = np.random.default_rng(0)
    rows, cols = np.nonzero(free)
    k = rng.choice(len(rows), 300, replace=False)
    px, py = ox + (cols[k] + 0.5) * res, oy + (img.height - rows[k] - 0.5) * res
    edt = ndimage.distance_transform_edt(np.pad(free, 1))[1:-1, 1:-1][rows[k], cols[k]]
    # the centre-to-centre distance transform brackets the distance to the nearest cell square
    lo, hi = (edt - math.sqrt(0.5)) * res, (edt - 0.5) * res
    got = shapely.distance(shapely.points(px, py), world.geometry())
    fits = lo > 0.25
    assert fits.sum() > 100
    assert np.all(got[fits] >= lo[fits] - res - 1e-9) and np.all(got[fits] <= hi[fits] + res + 1e-9)
    # the start holds the robot, in free space
    x, y, _ = world.start
    assert world.clearance(x, y) > 0.25
    c = int((x - ox) / res)
    r = img.height - 1 - int((y - oy) / res)
    assert free[r, c]

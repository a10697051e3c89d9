"""Map files: PNG/PGM images and ROS map_server YAML (tether.world.maps)."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
import pytest
import yaml
from PIL import Image

from tether.errors import MapError
from tether.world.grid import OccupancyGrid
from tether.world.maps import load_map, load_map_layers, read_image, save_map

SHARED_MAPS = Path(__file__).parents[1] / ".." / "shared" / "maps"
SHARED_NAMES = ["grass", "offices", "open"]


def shared_map(name: str) -> Path:
    path = SHARED_MAPS / f"{name}.png"
    if not path.is_file():
        pytest.skip(f"shared test maps not available ({SHARED_MAPS} is absent)")
    return path


# --------------------------------------------------------------------------- oracles


def oracle_masks(
    pixels: np.ndarray, maxval: int, occ_th: float, free_th: float, negate: bool
) -> tuple[np.ndarray, np.ndarray]:
    """Pixel-by-pixel classification written as plain loops (ROS map_server rules).

    ``pixels`` is ``(rows, cols[, channels])`` with row 0 the top of the map;
    returns ``occupied[ix, iy]`` and ``unknown[ix, iy]``.
    """
    rows, cols = pixels.shape[:2]
    occupied = np.zeros((cols, rows), dtype=bool)
    unknown = np.zeros((cols, rows), dtype=bool)
    for row in range(rows):
        for col in range(cols):
            value = pixels[row, col]
            if np.ndim(value):
                value = sum(float(v) for v in value[:3]) / len(value[:3])
            p = float(value) / maxval if negate else (maxval - float(value)) / maxval
            ix, iy = col, rows - 1 - row  # top row is the largest y
            occupied[ix, iy] = p > occ_th
            unknown[ix, iy] = free_th <= p <= occ_th
    return occupied, unknown


def pgm_bytes(pixels: np.ndarray, maxval: int, *, plain: bool) -> bytes:
    """Hand-written PGM encoder (independent of the loader), with comments."""
    rows, cols = pixels.shape
    header = f"{'P2' if plain else 'P5'}\n# a comment\n{cols} {rows}\n# another\n{maxval}\n"
    if plain:
        body = "\n".join(" ".join(str(int(v)) for v in row) for row in pixels) + "\n"
        return header.encode() + body.encode()
    dtype = ">u2" if maxval > 255 else "u1"
    return header.encode() + pixels.astype(dtype).tobytes()


def write_yaml(path: Path, doc: dict) -> Path:
    path.write_text(yaml.safe_dump(doc), encoding="utf-8")
    return path


# --------------------------------------------------------------------------- shared maps


@pytest.mark.parametrize("name", SHARED_NAMES)
def test_shared_map_loads_with_expected_shape_and_obstacles(name: str) -> None:
    path = shared_map(name)
    grid = load_map(path, resolution_m=0.1)
    assert grid.shape == (800, 600)
    np.testing.assert_allclose(grid.size_m, [80.0, 60.0])
    np.testing.assert_allclose(grid.origin_m, [0.0, 0.0])
    rgb = np.asarray(Image.open(path).convert("RGB"))
    black = (rgb == 0).all(axis=2)  # the README's definition of an obstacle
    fraction = grid.occupied.mean()
    assert 0.05 < fraction < 0.8
    # every black pixel is occupied, at the flipped/transposed position
    assert np.all(grid.occupied[black[::-1].T])
    # grey anti-aliasing pixels are the only other occupied/unknown cells
    assert abs(fraction - black.mean()) < 0.01


@pytest.mark.parametrize("name", SHARED_NAMES)
def test_shared_map_png_and_pgm_agree(name: str, tmp_path: Path) -> None:
    path = shared_map(name)
    grey = Image.open(path).convert("L")
    grey.save(tmp_path / "map.pgm")  # Pillow writes a binary P5 PGM
    pixels = np.asarray(grey)
    (tmp_path / "plain.pgm").write_bytes(pgm_bytes(pixels, 255, plain=True))
    png = load_map_layers(path, resolution_m=0.1)
    for pgm_name in ("map.pgm", "plain.pgm"):
        pgm = load_map_layers(tmp_path / pgm_name, resolution_m=0.1)
        np.testing.assert_array_equal(pgm.grid.occupied, png.grid.occupied)
        np.testing.assert_array_equal(pgm.unknown, png.unknown)


def test_shared_map_bare_image_defaults_to_one_metre_cells() -> None:
    grid = load_map(shared_map("open"))
    assert grid.resolution_m == 1.0
    np.testing.assert_allclose(grid.size_m, [800.0, 600.0])


# --------------------------------------------------------------------------- semantics


def test_top_left_black_pixel_is_max_y_min_x_cell(tmp_path: Path) -> None:
    # 3 columns x 2 rows; only the top-left pixel is black
    pixels = np.full((2, 3), 255, dtype=np.uint8)
    pixels[0, 0] = 0
    Image.fromarray(pixels).save(tmp_path / "tiny.png")
    grid = load_map(tmp_path / "tiny.png", resolution_m=0.5, origin_m=(10.0, -2.0))
    assert grid.shape == (3, 2)
    expected = np.zeros((3, 2), dtype=bool)
    expected[0, 1] = True  # min x, max y
    np.testing.assert_array_equal(grid.occupied, expected)
    # and the world point of the top-left corner region lies in that cell
    assert grid.is_occupied(np.array([[10.1, -2.0 + 0.9]]))[0]
    assert not grid.is_occupied(np.array([[11.4, -2.0 + 0.9]]))[0]


def test_known_pixels_thresholds_and_negate(tmp_path: Path) -> None:
    # p = (255 - v) / 255:  v=0 -> 1.0, 60 -> 0.765, 100 -> 0.608, 200 -> 0.216,
    # 210 -> 0.176, 255 -> 0
    pixels = np.array([[0, 60, 100], [200, 210, 255]], dtype=np.uint8)
    Image.fromarray(pixels).save(tmp_path / "t.png")
    layers = load_map_layers(tmp_path / "t.png")
    # grid layout [ix, iy]: iy = 1 is the top row
    np.testing.assert_array_equal(layers.occupied, [[False, True], [False, True], [False, False]])
    np.testing.assert_array_equal(layers.unknown, [[True, False], [False, False], [False, True]])
    np.testing.assert_array_equal(layers.grid.occupied, layers.occupied | layers.unknown)
    neg = load_map_layers(tmp_path / "t.png", negate=True)
    # negate: p = v / 255 -> 0, 0.235, 0.392, 0.784, 0.824, 1.0
    np.testing.assert_array_equal(neg.occupied, [[True, False], [True, False], [True, False]])
    np.testing.assert_array_equal(neg.unknown, [[False, False], [False, True], [False, True]])


@pytest.mark.parametrize("seed", range(12))
def test_random_images_match_loop_oracle(seed: int, tmp_path: Path) -> None:
    rng = np.random.default_rng(seed)
    rows, cols = rng.integers(1, 9, size=2)
    channels = [None, 3, 4][seed % 3]
    shape = (rows, cols) if channels is None else (rows, cols, channels)
    pixels = rng.integers(0, 256, size=shape).astype(np.uint8)
    free_th, occ_th = np.sort(rng.uniform(0, 1, size=2))
    negate = bool(rng.integers(2))
    Image.fromarray(pixels).save(tmp_path / "r.png")
    layers = load_map_layers(
        tmp_path / "r.png", occupied_thresh=occ_th, free_thresh=free_th, negate=negate
    )
    occupied, unknown = oracle_masks(pixels, 255, occ_th, free_th, negate)
    np.testing.assert_array_equal(layers.occupied, occupied)
    np.testing.assert_array_equal(layers.unknown, unknown)


@pytest.mark.parametrize("maxval", [255, 1000, 65535])
@pytest.mark.parametrize("plain", [False, True])
def test_pgm_reader_matches_pillow(maxval: int, plain: bool, tmp_path: Path) -> None:
    rng = np.random.default_rng(maxval + plain)
    pixels = rng.integers(0, maxval + 1, size=(5, 7))
    data = pgm_bytes(pixels, maxval, plain=plain)
    (tmp_path / "m.pgm").write_bytes(data)
    values, got_max = read_image(tmp_path / "m.pgm")
    assert got_max == maxval
    np.testing.assert_array_equal(values, pixels)
    # Pillow rescales other maxvals to 16 bit: compare the fractions of full scale
    pillow = np.asarray(Image.open(io.BytesIO(data))).astype(float)
    np.testing.assert_allclose(
        values / maxval, pillow / (255 if maxval == 255 else 65535), atol=1e-4
    )
    layers = load_map_layers(tmp_path / "m.pgm")
    occupied, unknown = oracle_masks(pixels, maxval, 0.65, 0.196, False)
    np.testing.assert_array_equal(layers.occupied, occupied)
    np.testing.assert_array_equal(layers.unknown, unknown)


def test_sixteen_bit_png(tmp_path: Path) -> None:
    pixels = np.array([[0, 30000, 65535], [65535, 65535, 1000]], dtype=np.uint16)
    Image.fromarray(pixels).save(tmp_path / "deep.png")
    values, maxval = read_image(tmp_path / "deep.png")
    assert maxval == 65535
    np.testing.assert_array_equal(values, pixels)
    occupied, unknown = oracle_masks(pixels, 65535, 0.65, 0.196, False)
    layers = load_map_layers(tmp_path / "deep.png")
    np.testing.assert_array_equal(layers.occupied, occupied)
    np.testing.assert_array_equal(layers.unknown, unknown)


def test_alpha_channel_is_ignored(tmp_path: Path) -> None:
    rgba = np.zeros((2, 2, 4), dtype=np.uint8)
    rgba[..., :3] = [[[0, 0, 0], [255, 255, 255]], [[255, 255, 255], [0, 0, 0]]]
    rgba[..., 3] = [[0, 255], [255, 0]]  # transparent black pixels
    Image.fromarray(rgba, mode="RGBA").save(tmp_path / "a.png")
    grid = load_map(tmp_path / "a.png")
    np.testing.assert_array_equal(grid.occupied, [[False, True], [True, False]])


# --------------------------------------------------------------------------- ROS YAML


@pytest.mark.parametrize("seed", range(8))
def test_save_load_round_trip(seed: int, tmp_path: Path) -> None:
    rng = np.random.default_rng(seed)
    shape = tuple(rng.integers(1, 40, size=2))
    occupied = rng.random(shape) < rng.uniform(0, 1)
    resolution = float(rng.uniform(0.01, 2.0))
    origin = rng.normal(scale=50.0, size=2)
    grid = OccupancyGrid(occupied, resolution, origin)
    unknown = (rng.random(shape) < 0.2) & ~occupied
    path = save_map(grid, tmp_path / "sub" / "saved.yaml", unknown=unknown)
    doc = yaml.safe_load(path.read_text())
    assert doc["image"] == "saved.pgm"  # relative to the YAML
    back = load_map_layers(path)
    assert back.grid.resolution_m == resolution
    np.testing.assert_array_equal(back.grid.origin_m, origin)
    np.testing.assert_array_equal(back.occupied, occupied)
    np.testing.assert_array_equal(back.unknown, unknown)
    np.testing.assert_array_equal(back.grid.occupied, occupied | unknown)
    # the PGM is readable by an independent reader with the same orientation
    image = np.asarray(Image.open(path.with_suffix(".pgm")))
    np.testing.assert_array_equal(image == 0, occupied.T[::-1])


def test_yaml_fields_are_honoured(tmp_path: Path) -> None:
    pixels = np.array([[0, 120, 255]], dtype=np.uint8)  # p = 1.0, 0.53, 0
    (tmp_path / "img").mkdir()
    Image.fromarray(pixels).save(tmp_path / "img" / "m.png")
    base = {"image": "img/m.png", "resolution": 0.05, "origin": [1.5, -3.0, 0.0]}
    grid = load_map(write_yaml(tmp_path / "a.yaml", base))
    assert grid.resolution_m == 0.05
    np.testing.assert_array_equal(grid.origin_m, [1.5, -3.0])
    np.testing.assert_array_equal(grid.occupied[:, 0], [True, True, False])
    strict = load_map_layers(write_yaml(tmp_path / "b.yaml", {**base, "free_thresh": 0.6}))
    np.testing.assert_array_equal(strict.unknown[:, 0], [False, False, False])
    np.testing.assert_array_equal(strict.occupied[:, 0], [True, False, False])
    neg = load_map(write_yaml(tmp_path / "c.yaml", {**base, "negate": 1}))
    np.testing.assert_array_equal(neg.occupied[:, 0], [False, True, True])
    scaled = load_map(write_yaml(tmp_path / "d.yaml", {**base, "mode": "scale"}))
    np.testing.assert_array_equal(scaled.occupied, grid.occupied)
    # keyword arguments override resolution and origin; unknown keys are ignored
    over = load_map(
        write_yaml(tmp_path / "e.yaml", {**base, "whatever": 3}), resolution_m=2.0, origin_m=(0, 0)
    )
    assert over.resolution_m == 2.0
    np.testing.assert_array_equal(over.origin_m, [0.0, 0.0])


def test_exponent_floats_in_a_map_yaml_are_numbers(tmp_path: Path) -> None:
    """ROS's yaml-cpp (YAML 1.2) reads ``resolution: 5e-2`` as a number; so do we."""
    Image.fromarray(np.array([[0, 255]], dtype=np.uint8)).save(tmp_path / "m.png")
    path = tmp_path / "m.yaml"
    path.write_text("image: m.png\nresolution: 5e-2\norigin: [1e1, 0, 0]\n")
    grid = load_map(path)
    assert grid.resolution_m == 0.05
    np.testing.assert_array_equal(grid.origin_m, [10.0, 0.0])


def test_raw_mode_reads_percent_occupancy(tmp_path: Path) -> None:
    pixels = np.array([[0, 10, 50, 70, 100, 255]], dtype=np.uint8)
    Image.fromarray(pixels).save(tmp_path / "raw.png")
    doc = {"image": "raw.png", "resolution": 1, "origin": [0, 0, 0], "mode": "raw"}
    layers = load_map_layers(write_yaml(tmp_path / "raw.yaml", {**doc, "negate": 1}))
    np.testing.assert_array_equal(layers.occupied[:, 0], [False, False, False, True, True, False])
    np.testing.assert_array_equal(layers.unknown[:, 0], [False, False, True, False, False, True])


# --------------------------------------------------------------------------- errors


def assert_one_line(exc: pytest.ExceptionInfo, *parts: str) -> None:
    message = str(exc.value)
    assert "\n" not in message
    for part in parts:
        assert part in message, (part, message)


@pytest.fixture
def tiny_png(tmp_path: Path) -> Path:
    Image.fromarray(np.array([[0, 255]], dtype=np.uint8)).save(tmp_path / "ok.png")
    return tmp_path / "ok.png"


def test_missing_and_unreadable_images(tmp_path: Path) -> None:
    with pytest.raises(MapError) as exc:
        load_map(tmp_path / "missing.png")
    assert_one_line(exc, "missing.png", "file not found")
    (tmp_path / "bad.png").write_bytes(b"this is not an image\n\x00\x01")
    with pytest.raises(MapError) as exc:
        load_map(tmp_path / "bad.png")
    assert_one_line(exc, "bad.png", "not a readable PNG/PGM image", "cannot identify")
    (tmp_path / "short.pgm").write_bytes(b"P5\n4 4\n255\n\x00\x00")
    with pytest.raises(MapError) as exc:
        load_map(tmp_path / "short.pgm")
    assert_one_line(exc, "short.pgm", "truncated")
    (tmp_path / "over.pgm").write_bytes(b"P2\n2 1\n100\n0 200\n")
    with pytest.raises(MapError) as exc:
        load_map(tmp_path / "over.pgm")
    assert_one_line(exc, "over.pgm", "maxval")
    (tmp_path / "neg.pgm").write_bytes(b"P2\n2 1\n255\n0 -3\n")
    with pytest.raises(MapError) as exc:
        load_map(tmp_path / "neg.pgm")
    assert_one_line(exc, "neg.pgm", "negative")
    (tmp_path / "nohead.pgm").write_bytes(b"P5\n4\n")
    with pytest.raises(MapError) as exc:
        load_map(tmp_path / "nohead.pgm")
    assert_one_line(exc, "nohead.pgm", "header")


def test_bad_keyword_arguments_for_bare_image(tiny_png: Path) -> None:
    with pytest.raises(MapError) as exc:
        load_map(tiny_png, resolution_m=-1)
    assert_one_line(exc, "ok.png", "resolution_m", "positive", "-1")
    with pytest.raises(MapError) as exc:
        load_map(tiny_png, occupied_thresh=0.1, free_thresh=0.5)
    assert_one_line(exc, "ok.png", "free_thresh", "occupied_thresh")


BAD_YAML = [
    ({"resolution": 0.1, "origin": [0, 0, 0]}, "image", "required key missing"),
    ({"image": "ok.png", "origin": [0, 0, 0]}, "resolution", "required key missing"),
    ({"image": "foo.png", "resolution": 0.1}, "image", "'foo.png' not found next to the YAML"),
    ({"image": 3, "resolution": 0.1}, "image", "file name"),
    ({"image": "ok.png", "resolution": -1}, "resolution", "must be a positive number (got -1)"),
    ({"image": "ok.png", "resolution": "fine"}, "resolution", "positive number"),
    ({"image": "ok.png", "resolution": True}, "resolution", "positive number"),
    ({"image": "ok.png", "resolution": 1, "origin": [0, 0, 0.3]}, "origin", "yaw must be 0"),
    ({"image": "ok.png", "resolution": 1, "origin": [0]}, "origin", "[x, y, yaw]"),
    ({"image": "ok.png", "resolution": 1, "origin": "0 0 0"}, "origin", "[x, y, yaw]"),
    ({"image": "ok.png", "resolution": 1, "origin": [0, "a", 0]}, "origin", "number"),
    ({"image": "ok.png", "resolution": 1, "occupied_thresh": 1.5}, "occupied_thresh", "0 and 1"),
    ({"image": "ok.png", "resolution": 1, "free_thresh": 0.9}, "free_thresh", "occupied_thresh"),
    ({"image": "ok.png", "resolution": 1, "negate": 2}, "negate", "0/1 or true/false"),
    ({"image": "ok.png", "resolution": 1, "mode": "fancy"}, "mode", "trinary, scale, raw"),
]


@pytest.mark.parametrize(("doc", "field", "text"), BAD_YAML)
def test_bad_yaml_fields(doc: dict, field: str, text: str, tiny_png: Path) -> None:
    path = write_yaml(tiny_png.parent / "x.yaml", doc)
    with pytest.raises(MapError) as exc:
        load_map(path)
    assert_one_line(exc, "x.yaml", f"{field}:", text)


def test_malformed_yaml_documents(tiny_png: Path) -> None:
    folder = tiny_png.parent
    (folder / "syntax.yaml").write_text("image: ok.png\nresolution: [0.1\n")
    with pytest.raises(MapError) as exc:
        load_map(folder / "syntax.yaml")
    assert_one_line(exc, "syntax.yaml", "not valid YAML", "line")
    (folder / "list.yaml").write_text("- image\n- resolution\n")
    with pytest.raises(MapError) as exc:
        load_map(folder / "list.yaml")
    assert_one_line(exc, "list.yaml", "mapping")
    (folder / "broken.png").write_bytes(b"\x89PNG\r\n\x1a\n garbage")
    write_yaml(folder / "img.yaml", {"image": "broken.png", "resolution": 1})
    with pytest.raises(MapError) as exc:
        load_map(folder / "img.yaml")
    assert_one_line(exc, "img.yaml", "image:", "broken.png", "not a readable PNG/PGM image")
    with pytest.raises(MapError) as exc:
        load_map(folder / "absent.yaml")
    assert_one_line(exc, "absent.yaml", "file not found")


def test_save_map_rejects_3d_grid(tmp_path: Path) -> None:
    grid = OccupancyGrid(np.zeros((2, 2, 2), dtype=bool))
    with pytest.raises(MapError) as exc:
        save_map(grid, tmp_path / "cube.yaml")
    assert_one_line(exc, "cube.yaml", "2-D")

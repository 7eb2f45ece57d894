"""The Python module (docs/python.md): a bake's layer equals the EXR it wrote, the progress
callable sees every stage, and a bad key raises SceneError naming file, line and key.
Run by ctest (test python_module) when the module is built (-DSNOWBAKE_PYTHON=ON)."""
import os

import numpy as np
import pytest

snowbake = pytest.importorskip("snowbake", reason="the snowbake module is not built (cmake -DSNOWBAKE_PYTHON=ON)")

SMALL = {"terrain.size": 64, "season.days": 20, "outputs.frames_days": [10]}


def read_exr_float32(path):
    """The EXR through OpenImageIO's Python binding when installed; else the test skips."""
    oiio = pytest.importorskip("OpenImageIO", reason="OpenImageIO's Python binding (python3-openimageio) is not installed")
    image = oiio.ImageInput.open(path)
    pixels = image.read_image(0, 0, 0, 1, "float")
    image.close()
    return np.asarray(pixels, dtype=np.float32).reshape(pixels.shape[0], pixels.shape[1])


def test_builtin_64_bake_layer_is_the_exr_bit_for_bit_and_progress_sees_every_stage(tmp_path):
    seen = []
    result = snowbake.bake("preset:default", out=str(tmp_path / "o"), overrides=SMALL, threads=2, progress=seen.append)
    depth = result.layer("depth")
    assert depth.dtype == np.float32 and depth.shape == (64, 64)
    assert np.all(np.isfinite(depth)) and depth.min() >= 0 and depth.max() > 0
    assert result.layer("depth", 10).shape == (64, 64)
    stages = {e["stage"] for e in seen if e["type"] == "progress" and e["fraction"] == 1}
    assert {"scene", "terrain", "precompute", "season", "outputs", "manifest"} <= stages
    assert len(result.manifest["files"]) == len(result.files) - 1
    assert result.manifest["scene"]["resolved"] == "scene.resolved.toml"
    exr = read_exr_float32(os.path.join(result.out, "depth.exr"))
    assert exr.tobytes() == depth.tobytes()


def test_plan_lists_the_files_the_bake_then_writes_and_writes_nothing(tmp_path):
    out = tmp_path / "o"
    plan = snowbake.plan("preset:default", out=str(out), overrides=SMALL, threads=2)
    assert not out.exists()
    assert plan["grid"] == [64, 64] and plan["memory"]["peak_bytes"] > 0 and plan["time_class"]
    assert {s["name"] for s in plan["stages"]} >= {"terrain", "season", "outputs", "manifest"}
    planned = {f["path"] for f in plan["files"] if not f["condition"]}
    result = snowbake.bake("preset:default", out=str(out), overrides=SMALL, threads=2)
    written = {os.path.relpath(os.path.join(d, f), out) for d, _, fs in os.walk(out) for f in fs}
    assert planned <= written
    assert written - planned <= {f["path"] for f in plan["files"] if f["condition"]}, written - planned
    assert len(written) == len(result.files)


def test_bad_key_raises_scene_error_with_file_line_and_key(tmp_path):
    scene = tmp_path / "bad.toml"
    scene.write_text('[terrain]\nbuiltin = "ridged"\nsize = 64\n[season]\ndayz = 3\n')
    with pytest.raises(snowbake.SceneError) as error:
        snowbake.bake(str(scene), out=str(tmp_path / "o"))
    message = str(error.value)
    assert str(scene) in message and ":5:" in message and "season.dayz" in message, message
    assert not (tmp_path / "o").exists()


def test_info_reads_the_builtin_terrain():
    info = snowbake.info("builtin:ridged")
    assert info["width"] > 0 and info["height"] > 0


def test_sigint_during_a_bake_raises_keyboard_interrupt_and_writes_no_manifest(tmp_path):
    """Ctrl-C from a terminal is SIGINT to the process: the bake stops between steps, Python gets KeyboardInterrupt."""
    import signal
    import subprocess
    import sys
    import time
    out = tmp_path / "o"
    code = (
        "import snowbake, sys\n"
        "try:\n"
        "    snowbake.bake('preset:default', out=sys.argv[1], threads=2, progress=lambda e: print(e.get('event', ''), flush=True),\n"
        "                  overrides={'terrain.size': 256, 'season.days': 120, 'outputs.frames_days': list(range(1, 30))})\n"
        "except KeyboardInterrupt as e:\n"
        "    print('KeyboardInterrupt:', e, flush=True)\n"
        "    sys.exit(3)\n"
    )
    child = subprocess.Popen([sys.executable, "-c", code, str(out)], stdout=subprocess.PIPE, text=True, env=os.environ)
    for line in child.stdout:  # once the season writes frames
        if line.strip() == "frame":
            break
    start = time.monotonic()
    child.send_signal(signal.SIGINT)
    rest, _ = child.communicate(timeout=60)
    assert child.returncode == 3, rest
    assert "KeyboardInterrupt: interrupted by SIGINT" in rest, rest
    assert time.monotonic() - start < 20
    assert not (out / "manifest.json").exists()
    assert not [p for p in out.rglob("*") if ".tmp" in p.name]

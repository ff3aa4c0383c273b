"""Bounded fuzzing of what mcvol-render reads: the scene parser
(mcvol.scenefile.parse_scene) and every reader of the scene's input files
(.vti, .mha, .nrrd, .nii, .nii.gz, .tif, OME-TIFF, raw). Every input must end
in a result or a SceneError (a clear message naming the key), never another
exception (a traceback), a crash or a hang.

The inputs come from python3-hypothesis, derandomized (the same examples on
every run): scenes are the repository's scene files with values replaced,
keys removed or added, and free-form JSON; files are small valid files of each
format with bytes changed, inserted or cut. The examples are bounded in number
and the whole test in time (about 30 s on 2 cores).
"""

import json
import math
import os
import shutil
import signal
import struct
import sys
import tempfile
import time
import traceback

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import numpy as np

try:
    from hypothesis import HealthCheck, Phase, given, settings
    from hypothesis import strategies as st
    from hypothesis.configuration import set_hypothesis_home_dir
except ImportError:
    print("python3-hypothesis is not installed (scripts/deps.sh installs it)")
    sys.exit(125)

from vtkmodules.util.numpy_support import numpy_to_vtk
from vtkmodules.vtkCommonDataModel import vtkImageData

from mcvol.scenefile import Presets, RenderError, SceneError, parse_scene
from mcvol.scenefile.errors import ErrorCollector
from mcvol.scenefile.parse import parse_input
from mcvol.scenefile.readers import read_inputs
from mcvolTesting import Checker

HERE = os.path.dirname(os.path.abspath(__file__))
TOP = os.path.dirname(os.path.dirname(HERE))
SCENES = os.path.join(TOP, "Data", "scenes")
PRESETS = Presets(os.path.join(TOP, "Data", "presets.json"))
# A hang is an example that runs longer than this (seconds); a normal one
# takes milliseconds.
EXAMPLE_LIMIT = 10

t = Checker()
# Hypothesis keeps caches in a folder: a temporary one, not the source tree.
hypothesis_home = tempfile.mkdtemp(prefix="mcvol-hypothesis-")
set_hypothesis_home_dir(hypothesis_home)


class Hang(Exception):
    pass


def on_alarm(signum, frame):
    raise Hang()


signal.signal(signal.SIGALRM, on_alarm)


def outcome(call):
    """'ok', 'error: message' (a SceneError), or 'BAD: ...' (anything else)."""
    signal.alarm(EXAMPLE_LIMIT)
    try:
        call()
        return "ok"
    except SceneError as e:
        text = "%s: %s" % (e.key, e.message)
        if "\n" in e.message or not e.message.strip():
            return "BAD: message not one line: %r" % text
        return "error: " + text
    except Hang:
        return "BAD: no result after %d s" % EXAMPLE_LIMIT
    except BaseException:  # noqa: B902 (RecursionError, MemoryError, ...: all are failures)
        return "BAD: " + traceback.format_exc(limit=4).strip().splitlines()[-1]
    finally:
        signal.alarm(0)


# ---- Scenes -------------------------------------------------------------------

json_scalars = st.one_of(
    st.none(), st.booleans(), st.integers(-(2**70), 2**70),
    st.floats(allow_nan=True, allow_infinity=True), st.text(max_size=12),
    st.sampled_from(["", "density", "max", "mix", "composite", "1-dda", "n-dda", "linear", "cubic", "cpu", "cuda",
                     "Grayscale", "Solid Red", "membranes", "../microscopy.vti", "/", ".", "demo", "x.nii"]),
    st.sampled_from([0, 1, -1, 0.5, 1e-300, 1e300, 2**31, 33, 4096, 16385]))
json_values = st.recursive(
    json_scalars,
    lambda inner: st.one_of(st.lists(inner, max_size=6), st.dictionaries(st.text(max_size=8), inner, max_size=5)),
    max_leaves=20)


def load_scenes():
    out = []
    for name in sorted(os.listdir(SCENES)):
        if name.endswith(".json"):
            with open(os.path.join(SCENES, name)) as f:
                out.append(json.load(f))
    return out


BASE_SCENES = load_scenes()


def paths(value, prefix=()):
    """Every path (a tuple of keys and indices) inside a JSON value."""
    yield prefix
    if isinstance(value, dict):
        for k, v in value.items():
            yield from paths(v, prefix + (k,))
    elif isinstance(value, list):
        for i, v in enumerate(value):
            yield from paths(v, prefix + (i,))


def mutate(scene, edits):
    """`scene` with each edit (path index, action, value) applied."""
    scene = json.loads(json.dumps(scene))
    for which, action, value in edits:
        all_paths = list(paths(scene))
        path = all_paths[which % len(all_paths)]
        if not path:
            continue
        parent = scene
        for k in path[:-1]:
            parent = parent[k]
        last = path[-1]
        if action == "replace":
            parent[last] = value
        elif action == "delete":
            del parent[last]
        elif action == "add" and isinstance(parent, dict):
            parent[str(value)[:8]] = value
        elif action == "add" and isinstance(parent, list):
            parent.append(value)
    return scene


scene_outcomes = {}


def record_scene(label, scene):
    result = outcome(lambda: parse_scene(scene, SCENES, PRESETS))
    scene_outcomes.setdefault(result.split(":")[0], 0)
    scene_outcomes[result.split(":")[0]] += 1
    if result.startswith("BAD"):
        t.check(False, "%s: %s\n  scene: %s" % (label, result, json.dumps(scene)[:400]))


edit = st.tuples(st.integers(0, 10**6), st.sampled_from(["replace", "delete", "add"]), json_values)
fuzz_settings = dict(derandomize=True, deadline=None, database=None, phases=[Phase.generate],
                     suppress_health_check=list(HealthCheck))


@settings(max_examples=400, **fuzz_settings)
@given(st.integers(0, len(BASE_SCENES) - 1), st.lists(edit, min_size=1, max_size=4))
def fuzz_mutated_scenes(index, edits):
    record_scene("mutated scene", mutate(BASE_SCENES[index], edits))


@settings(max_examples=200, **fuzz_settings)
@given(json_values)
def fuzz_free_scenes(value):
    record_scene("free-form scene", value)
    record_scene("free-form input", {"input": value})
    record_scene("free-form channels", {"input": {"demo": "figure3"}, "channels": value})


fuzz_mutated_scenes()
fuzz_free_scenes()

# Nesting as deep as JSON allows, and deeper than Python can walk.
def nested(depth):
    value = []
    for _ in range(depth):
        value = [value]
    return value


for depth in (30, 40, 100000):
    record_scene("nested %d deep" % depth, {"input": {"demo": "figure3"}, "camera": {"position": nested(depth)}})
t.check(scene_outcomes.get("ok", 0) > 20 and scene_outcomes.get("error", 0) > 200,
        "scenes: both valid and refused ones were generated (%s)" % scene_outcomes)
print("scenes: %s" % scene_outcomes)

# ---- Files ----------------------------------------------------------------------

work = tempfile.mkdtemp(prefix="mcvol-fuzz-")


def write_base_files():
    """name -> (bytes, scene input naming the file). Small files (6x5x4 int16)."""
    from vtkmodules.vtkIOImage import vtkMetaImageWriter, vtkNIFTIImageWriter
    from vtkmodules.vtkIOXML import vtkXMLImageDataWriter

    values = (np.arange(6 * 5 * 4).reshape(4, 5, 6) * 7 % 300).astype(np.int16)
    image = vtkImageData()
    image.SetDimensions(6, 5, 4)
    image.SetSpacing(0.5, 1.0, 2.0)
    image.GetPointData().SetScalars(numpy_to_vtk(values.ravel(), deep=True))
    image.GetPointData().GetScalars().SetName("density")
    files = {}
    for name, writer in (("base.vti", vtkXMLImageDataWriter()), ("ascii.vti", vtkXMLImageDataWriter()),
                         ("base.mha", vtkMetaImageWriter()), ("base.nii", vtkNIFTIImageWriter()),
                         ("base.nii.gz", vtkNIFTIImageWriter())):
        writer.SetInputData(image)
        writer.SetFileName(os.path.join(work, name))
        if name == "base.mha":
            writer.SetCompression(False)
        if name == "ascii.vti":
            writer.SetDataModeToAscii()
        writer.Write()
    with open(os.path.join(work, "base.nrrd"), "wb") as f:
        f.write(b"NRRD0004\ntype: short\ndimension: 3\nsizes: 6 5 4\nspacings: 0.5 1 2\nencoding: raw\n"
                b"endian: little\n\n" + values.astype("<i2").tobytes())
    values.astype("<i2").tofile(os.path.join(work, "base.raw"))
    inputs = {name: name for name in ("base.vti", "ascii.vti", "base.mha", "base.nii", "base.nii.gz", "base.nrrd")}
    inputs["base.raw"] = {"raw": "base.raw", "dimensions": [6, 5, 4], "type": "int16"}
    try:
        import tifffile

        tifffile.imwrite(os.path.join(work, "base.tif"), values.astype(np.uint16))
        tifffile.imwrite(os.path.join(work, "base.ome.tif"),
                         np.stack([values, values[::-1]], axis=1).astype(np.uint16),
                         metadata={"axes": "ZCYX", "PhysicalSizeX": 0.5, "PhysicalSizeY": 1.0, "PhysicalSizeZ": 2.0})
        inputs["base.tif"] = "base.tif"
        inputs["base.ome.tif"] = "base.ome.tif"
    except ImportError:
        print("tifffile is not installed: the TIFF readers are not fuzzed")
    for name in inputs:
        with open(os.path.join(work, name), "rb") as f:
            files[name] = (f.read(), inputs[name])
    return files


BASE_FILES = write_base_files()
NAMES = sorted(BASE_FILES)
file_outcomes = {}


def read_file(spec):
    image = read_inputs(parse_input(spec, work), ErrorCollector())
    dims = image.GetDimensions()
    if not all(d >= 1 for d in dims) or image.GetPointData().GetNumberOfArrays() < 1:
        raise AssertionError("an image without voxels or arrays: %s" % (dims,))


def forked_outcome(call):
    """outcome(call) in a forked child: a crash (a signal) or a hang (no result
    after EXAMPLE_LIMIT s, the child killed) is a failure like a traceback."""
    read_end, write_end = os.pipe()
    pid = os.fork()
    if pid == 0:
        os.close(read_end)
        try:
            signal.alarm(0)
            text = outcome(call)
        except BaseException:  # noqa: B902
            text = "BAD: " + traceback.format_exc(limit=2).strip().splitlines()[-1]
        os.write(write_end, text.encode("utf-8", "replace")[:4000])
        os._exit(0)
    os.close(write_end)
    chunks = []
    deadline = time.monotonic() + EXAMPLE_LIMIT + 2
    import select
    while True:
        left = deadline - time.monotonic()
        ready, _, _ = select.select([read_end], [], [], max(left, 0))
        if not ready:
            os.kill(pid, signal.SIGKILL)
            os.waitpid(pid, 0)
            os.close(read_end)
            return "BAD: no result after %d s (hang)" % EXAMPLE_LIMIT
        chunk = os.read(read_end, 4096)
        if not chunk:
            break
        chunks.append(chunk)
    os.close(read_end)
    _, status = os.waitpid(pid, 0)
    if os.WIFSIGNALED(status):
        return "BAD: crashed with signal %d" % os.WTERMSIG(status)
    return b"".join(chunks).decode("utf-8", "replace") or "BAD: no result"


def record_file(label, name, data):
    original, spec = BASE_FILES[name]
    # The same file name and format as the base file, with the mutated bytes.
    target = os.path.join(work, (spec["raw"] if isinstance(spec, dict) else spec))
    fuzz_dir = os.path.join(work, "f")
    os.makedirs(fuzz_dir, exist_ok=True)
    path = os.path.join(fuzz_dir, os.path.basename(target))
    with open(path, "wb") as f:
        f.write(data)
    fuzz_spec = dict(spec, raw="f/" + spec["raw"]) if isinstance(spec, dict) else "f/" + spec
    result = forked_outcome(lambda: read_file(fuzz_spec))
    key = "%s %s" % (name, result.split(":")[0])
    file_outcomes[key] = file_outcomes.get(key, 0) + 1
    if result.startswith("BAD"):
        keep = os.path.join(work, "failing-%d-%s" % (len(t.failures), os.path.basename(target)))
        shutil.copy(path, keep)
        t.check(False, "%s %s: %s (kept as %s)" % (label, name, result, keep))


byte_edit = st.tuples(st.integers(0, 10**6), st.sampled_from(["set", "insert", "delete", "digit"]),
                      st.integers(0, 255))


def apply_bytes(data, edits, cut):
    b = bytearray(data)
    for pos, action, value in edits:
        if not b:
            break
        # Headers are where the structure is: half the edits land in the
        # first 400 bytes.
        p = pos % len(b) if pos % 2 else (pos // 2) % min(len(b), 400)
        if action == "set":
            b[p] = value
        elif action == "insert":
            b[p:p] = bytes([value])
        elif action == "delete":
            del b[p]
        elif action == "digit":
            b[p] = ord("0123456789-.e"[value % 13])
    if cut is not None:
        b = b[: cut % (len(b) + 1)]
    return bytes(b)


@settings(max_examples=700, **fuzz_settings)
@given(st.sampled_from(NAMES), st.lists(byte_edit, min_size=1, max_size=6), st.one_of(st.none(), st.integers(0, 10**6)))
def fuzz_files(name, edits, cut):
    record_file("mutated", name, apply_bytes(BASE_FILES[name][0], edits, cut))


for name in NAMES:
    record_file("unchanged", name, BASE_FILES[name][0])
    t.check(file_outcomes.get("%s ok" % name) == 1, "%s reads unmutated" % name)
    record_file("empty", name, b"")
fuzz_files()
print("files: %s" % dict(sorted(file_outcomes.items())))
for name in NAMES:
    t.check(file_outcomes.get("%s error" % name, 0) > 0, "%s: some mutations are refused with a message" % name)

shutil.rmtree(hypothesis_home, ignore_errors=True)
if t.failures:
    print("failing inputs kept in", work)
else:
    shutil.rmtree(work, ignore_errors=True)
t.finish()

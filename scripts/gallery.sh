#!/usr/bin/env bash
# Renders the gallery of real brain volumes (Documentation/gallery.md): every
# scene in Data/gallery/ in each of its blend modes, lit (the scene's
# "lighting") and unlit (without it), on the CPU, into
# Documentation/images/gallery/, and writes the timings to
# Documentation/gallery-timings.csv, Documentation/gallery-timings.md and the
# per-scene tables of Documentation/gallery.md.
#
#   bash scripts/gallery.sh [--build] [--size WxH] [--spp N] [--only SCENE] [--out DIR]
#
# --build      run scripts/build.sh even when build/ already holds mcvol-render
#              (by default the build is made only when it is missing)
# --size WxH   image size (default 320x320)
# --spp N      samples per pixel (default: each scene's samples_per_pixel)
# --only NAME  render only Data/gallery/NAME.json (its rows replace that
#              scene's rows in the timings; the other scenes' rows are kept)
# --out DIR    write the images and timings to DIR instead of Documentation/
#              (for trying out a scene; Documentation/ is left alone)
#
# The data comes from the Debian package mricron-data (installed here when
# missing, as scripts/deps.sh installs mcvol's packages: as root or with sudo).
# When a CUDA device is usable (mcvol-render --backend auto chooses it), every
# render is timed a second time on it; otherwise the timings say why not.
set -euo pipefail
top="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"

build=auto
size=320x320
spp=""
only=""
out=""
while [ $# -gt 0 ]; do
  case "$1" in
    --build) build=always ;;
    --size) size="$2"; shift ;;
    --spp) spp="$2"; shift ;;
    --only) only="$2"; shift ;;
    --out) out="$2"; shift ;;
    -h|--help) sed -n '2,23p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "gallery.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
  shift
done

# The data: Debian's mricron-data (templates and atlases of MRIcron).
if ! dpkg-query -W -f='${Status}' mricron-data 2>/dev/null | grep -q "install ok installed"; then
  echo "mcvol gallery: installing mricron-data"
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -q
  $SUDO apt-get install -y -q --no-install-recommends mricron-data
fi

# The build: scripts/build.sh (deps.sh, configure, build) when there is none,
# or always with --build.
render="$top/build/bin/mcvol-render"
if [ "$build" = always ] || [ ! -x "$render" ]; then
  bash "$top/scripts/build.sh"
fi
for d in "$top"/build/lib/python3*/site-packages; do
  if [ -d "$d/mcvol" ]; then export PYTHONPATH="$d${PYTHONPATH:+:$PYTHONPATH}"; fi
done
if ! command -v xvfb-run >/dev/null; then
  bash "$top/scripts/deps.sh"   # xvfb comes with mcvol's packages
fi

export MCVOL_GALLERY_TOP="$top" MCVOL_GALLERY_RENDER="$render" MCVOL_GALLERY_SIZE="$size"
export MCVOL_GALLERY_SPP="$spp" MCVOL_GALLERY_ONLY="$only" MCVOL_GALLERY_OUT="$out"
# One X server for all renders; one render at a time (each uses every core).
exec xvfb-run -a -s "-screen 0 1280x1024x24" /usr/bin/python3 - <<'PYTHON'
import csv, datetime, json, os, platform, re, subprocess, sys, tempfile, time

top = os.environ["MCVOL_GALLERY_TOP"]
render = os.environ["MCVOL_GALLERY_RENDER"]
size = os.environ["MCVOL_GALLERY_SIZE"]
spp_override = os.environ["MCVOL_GALLERY_SPP"]
only = os.environ["MCVOL_GALLERY_ONLY"]
out = os.environ["MCVOL_GALLERY_OUT"]

# The scenes and their blend modes. Composite adds the channels' images
# without occlusion between them and is not lit yet: with a context channel
# that is opaque (or a glass over the whole picture) the sum saturates to
# white, so it is rendered once, unlit, as an example (Documentation/gallery.md).
SCENES = [
    ("colin27-subcortical", ["density", "max", "mix"]),
    ("colin27-brodmann", ["density", "max", "mix", "composite"]),
    ("inia19-neuromaps", ["density", "max", "mix"]),
    ("mni152-whitematter", ["density", "max", "mix"]),
]
if only:
    SCENES = [s for s in SCENES if s[0] == only]
    if not SCENES:
        sys.exit("gallery.sh: no gallery scene named '%s'" % only)

docs = os.path.join(top, "Documentation")
image_dir = out or os.path.join(docs, "images", "gallery")
csv_path = os.path.join(out or docs, "gallery-timings.csv")
md_path = os.path.join(out or docs, "gallery-timings.md")
os.makedirs(image_dir, exist_ok=True)

SUMMARY = re.compile(r"(\d+) spp .* at (\d+)x(\d+), .*, (\w+) blend, (.*): ([0-9.]+) s -> ")


def run(scene_file, png, backend):
    """Renders; returns (summary match, wall seconds of the whole process)."""
    cmd = ["/usr/bin/python3", render, scene_file, "-o", png, "--backend", backend, "--size", size]
    if spp_override:
        cmd += ["--spp", spp_override]
    start = time.perf_counter()
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    wall = time.perf_counter() - start
    if p.returncode != 0:
        sys.exit("gallery.sh: %s failed (exit %d):\n%s" % (" ".join(cmd), p.returncode, p.stdout))
    line = p.stdout.strip().splitlines()[-1]
    m = SUMMARY.search(line)
    if not m:
        sys.exit("gallery.sh: cannot read the summary line of mcvol-render: %s" % line)
    return m, wall, line


def variants():
    for name, blends in SCENES:
        with open(os.path.join(top, "Data", "gallery", name + ".json")) as f:
            scene = json.load(f)
        for blend in blends:
            for lit in (True, False):
                if lit and (blend == "composite" or "lighting" not in scene):
                    continue
                v = dict(scene, blend=blend)
                if not lit:
                    v.pop("lighting", None)
                yield name, blend, lit, v


nproc = os.cpu_count()
try:
    nproc = int(subprocess.run(["nproc"], stdout=subprocess.PIPE, text=True).stdout)
except (OSError, ValueError):
    pass
cpu = platform.processor() or "unknown CPU"
try:
    with open("/proc/cpuinfo") as f:
        cpu = next(l.split(":", 1)[1].strip() for l in f if l.startswith("model name"))
except (OSError, StopIteration):
    pass
date = datetime.date.today().isoformat()
try:
    commit = subprocess.run(["git", "-C", top, "rev-parse", "--short", "HEAD"], stdout=subprocess.PIPE,
                            stderr=subprocess.DEVNULL, text=True).stdout.strip() or "unknown"
except OSError:
    commit = "unknown"

rows = []
with tempfile.TemporaryDirectory(prefix="mcvol-gallery-") as tmp:
    # Is there a CUDA device? Ask the mapper, with a tiny render on "auto".
    name0 = SCENES[0][0]
    probe = os.path.join(tmp, "probe.json")
    with open(os.path.join(top, "Data", "gallery", name0 + ".json")) as f:
        s = json.load(f)
    s.pop("lighting", None)
    s.update(image_size=[16, 16], samples_per_pixel=1)
    with open(probe, "w") as f:
        json.dump(s, f)
    m, _, _ = run(probe, os.path.join(tmp, "probe.png"), "auto")
    cuda_report = m.group(5)
    has_cuda = cuda_report.startswith("CUDA")
    print("gallery: backend auto -> %s" % cuda_report, flush=True)

    backends = ["cpu"] + (["auto"] if has_cuda else [])
    for name, blend, lit, v in variants():
        fn = os.path.join(tmp, "%s-%s-%s.json" % (name, blend, "lit" if lit else "unlit"))
        with open(fn, "w") as f:
            json.dump(v, f)
        for backend in backends:
            png = "%s-%s-%s.png" % (name, blend, "lit" if lit else "unlit")
            # The CUDA run is for its time only: the CPU image is the one kept.
            target = os.path.join(image_dir if backend == "cpu" else tmp, png)
            m, wall, line = run(fn, target, backend)
            print("gallery: " + line, flush=True)
            rows.append({
                "scene": name, "blend": blend, "lighting": "lit" if lit else "unlit",
                "backend": "CPU" if backend == "cpu" else m.group(5).split(" ")[0],
                "spp": int(m.group(1)), "size": "%sx%s" % (m.group(2), m.group(3)),
                "render_s": "%.2f" % float(m.group(6)), "process_s": "%.2f" % wall,
                "png_kb": os.path.getsize(target) // 1024 if backend == "cpu" else "",
                "image": png if backend == "cpu" else "",
                "nproc": nproc, "cpu": cpu, "date": date, "commit": commit,
            })

FIELDS = ["scene", "blend", "lighting", "backend", "spp", "size", "render_s", "process_s", "png_kb", "image",
          "nproc", "cpu", "date", "commit"]
# With --only, keep the other scenes' rows of the previous run.
rendered = {name for name, _ in SCENES}
if only and os.path.exists(csv_path):
    with open(csv_path) as f:
        old = [r for r in csv.DictReader(f) if r["scene"] not in rendered]
    rows = old + rows
rows = [{k: str(v) for k, v in r.items()} for r in rows]
order = {name: i for i, name in enumerate(["colin27-subcortical", "colin27-brodmann", "inia19-neuromaps",
                                            "mni152-whitematter"])}
rows.sort(key=lambda r: order.get(r["scene"], 99))
with open(csv_path, "w", newline="") as f:
    w = csv.DictWriter(f, fieldnames=FIELDS)
    w.writeheader()
    w.writerows(rows)

why = re.sub(r"^CPU backend \(auto: (.*)\)$", r"\1", cuda_report)
cuda_line = ("CUDA (`--backend auto`, rows with backend CUDA): %s." % cuda_report if has_cuda else
             "CUDA: not measured; `mcvol-render --backend auto` chose the CPU here: %s." % why)


def table(rs, with_scene):
    head = (["scene"] if with_scene else []) + ["blend", "lighting", "backend", "spp", "size", "render (s)",
                                                "process (s)", "PNG (KB)"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in rs:
        cells = ([r["scene"]] if with_scene else []) + [r["blend"], r["lighting"], r["backend"], str(r["spp"]),
                                                        r["size"], r["render_s"], r["process_s"], str(r["png_kb"])]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


machines = sorted({(r["nproc"], r["cpu"], r["date"], r["commit"]) for r in rows})
total_kb = sum(int(r["png_kb"]) for r in rows if r["png_kb"])
with open(md_path, "w") as f:
    f.write("# Gallery timings\n\n"
            "Written by `scripts/gallery.sh` (do not edit): one row per render of "
            "[the gallery](gallery.md). *render* is the accumulation time that "
            "mcvol-render prints on its summary line (all samples, CPU wall time); *process* is the "
            "whole mcvol-render process (Python start, reading and decompressing the NIfTI files, "
            "building the tables and macrocells, rendering, writing the PNG). One render at a time, "
            "under one Xvfb. Raw data: [gallery-timings.csv](gallery-timings.csv).\n\n")
    for n, c, d, k in machines:
        f.write("- %s, `nproc` = %s, %s, mcvol %s\n" % (c, n, d, k))
    f.write("- " + cuda_line + "\n")
    f.write("- Images: %d PNG files, %d KB in all.\n\n" % (len([r for r in rows if r["image"]]), total_kb))
    f.write(table(rows, True) + "\n")

# The per-scene tables of gallery.md, between its markers.
if not out:
    page = os.path.join(docs, "gallery.md")
    with open(page) as f:
        text = f.read()
    for name in {r["scene"] for r in rows}:
        rs = [r for r in rows if r["scene"] == name]
        n, c, d, k = rs[0]["nproc"], rs[0]["cpu"], rs[0]["date"], rs[0]["commit"]
        body = ("%s\n\n%s, `nproc` = %s, %s. %s\n" % (table(rs, False), c, n, d, cuda_line))
        pat = re.compile(r"(<!-- gallery-timings: %s -->\n).*?(<!-- /gallery-timings -->)" % re.escape(name), re.S)
        text, count = pat.subn(lambda mm: mm.group(1) + body + mm.group(2), text)
        if count != 1:
            print("gallery: no timings marker for %s in %s" % (name, page), file=sys.stderr)
    with open(page, "w") as f:
        f.write(text)

print("gallery: %d images (%d KB) in %s; timings in %s" % (len([r for r in rows if r["image"]]), total_kb,
                                                          image_dir, md_path))
PYTHON

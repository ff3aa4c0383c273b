"""pvserver: the representation renders on a pvserver (data and rendering
on the server, image delivered to the client) the same image as in builtin
mode. Run with the system Python (it starts pvserver and pvpython):
  python3 TestParaViewClientServer.py --pvpython pvpython --pvserver pvserver

The same seed gives the same image on the same backend, and the client asks
for lossless image delivery (CompressorConfig NULL; ParaView's default LZ4
level 3 reduces colours), so the two images must agree to within 1/255 per
channel (8-bit rounding).

Run under xvfb-run with -noreset (scripts/test.sh does): Xvfb otherwise
resets when its last client disconnects, and pvserver, started right after
the builtin pvpython exits, can hit the reset ("bad X server connection").
Both renders turn FXAA off (see mcvolParaViewTesting.make_view).
"""
import argparse
import os
import socket
import subprocess
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(os.path.dirname(HERE), "Python"))
from mcvolTesting import read_png_rgb  # noqa: E402


def free_port():
    with socket.socket() as s:
        s.bind(("localhost", 0))
        return s.getsockname()[1]


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--pvpython", default="pvpython")
    p.add_argument("--pvserver", default="pvserver")
    args = p.parse_args()
    env = dict(os.environ)
    env["PYTHONPATH"] = HERE + os.pathsep + env.get("PYTHONPATH", "")
    script = os.path.join(HERE, "ClientServerRender.py")
    tmp = tempfile.mkdtemp(prefix="mcvol-cs-")
    builtin_png, remote_png = os.path.join(tmp, "builtin.png"), os.path.join(tmp, "remote.png")

    res = subprocess.run([args.pvpython, script, builtin_png], env=env, stdout=subprocess.PIPE,
                         stderr=subprocess.STDOUT, text=True, timeout=300)
    print(res.stdout[-20000:] if res.returncode else "\n".join(l for l in res.stdout.splitlines() if ":" in l[:10]))
    if res.returncode:
        raise SystemExit("FAIL: builtin render exited with %d" % res.returncode)

    # An OME-Zarr for the server's reader (python3-zarr writes it; without
    # it that part is left out).
    zarr_args, zarr_line = [], None
    try:
        sys.path.insert(0, os.path.join(os.path.dirname(HERE), "Python"))
        import omezarrWriter as W

        values = np.zeros((2, 6, 8, 10), np.uint16)
        values[:, 1:5, 2:6, 2:8] = 1000
        omero = {"channels": [W.omero_channel("DAPI", "0000FF", 100, 900), W.omero_channel("GFP", "00FF00", 50, 500)]}
        zarr_args = [W.write(os.path.join(tmp, "cells.ome.zarr"), [values], "czyx", [[1, 1, 1, 1]], omero=omero)]
        zarr_line = "omezarr: mcvolOMEZarrReader ['DAPI', 'GFP'] [100.0, 0.0, 0.0, 0.35, 900.0, 0.0, 0.0, 1.0]"
    except ImportError:
        print("python3-zarr is not installed: the OME-Zarr part is left out")

    port = free_port()
    server = subprocess.Popen([args.pvserver, "--server-port=%d" % port], env=env, stdout=subprocess.PIPE,
                              stderr=subprocess.STDOUT, text=True, bufsize=1)
    server_log = []
    try:
        # Wait until the server listens (it prints "Accepting connection(s)");
        # probing the port instead would be taken for a client.
        deadline = time.time() + 60
        while time.time() < deadline:
            line = server.stdout.readline()
            if not line:
                break
            server_log.append(line)
            if "Accepting connection" in line:
                break
        res = subprocess.run([args.pvpython, script, remote_png, "localhost:%d" % port] + zarr_args, env=env,
                             stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=300)
        print(res.stdout[-3000:] if res.returncode else "\n".join(l for l in res.stdout.splitlines()
                                                                if l.startswith(("samples", "progress", "backend",
                                                                                 "omezarr"))))
        if res.returncode:
            server.terminate()
            log = "".join(server_log) + server.communicate(timeout=20)[0]
            print("pvserver output:\n" + log[-3000:])
            if "bad X server connection" in log:
                print("pvserver could not open the X display: run under xvfb-run -s '-noreset ...' (see the docstring)")
            raise SystemExit("FAIL: client-server render exited with %d" % res.returncode)
    finally:
        server.terminate()
        try:
            server.wait(timeout=20)
        except subprocess.TimeoutExpired:
            server.kill()

    a = read_png_rgb(builtin_png).astype(int)
    b = read_png_rgb(remote_png).astype(int)
    diff = np.abs(a - b)
    drawn = (a.sum(axis=2) > 30).mean()
    mean, worst = diff.mean(), diff.max()
    # 8 renders of 8 samples reach Maximum Total Samples (32) on the server;
    # the client's copy of the representation holds no data.
    served = "progress: samples 32 converged 1 psnr-positive 1"
    failures = 0
    for ok, msg in [
        (drawn > 0.05, "the builtin image shows the volume (%.1f%% of pixels)" % (100 * drawn)),
        (served in res.stdout, "the client reads the server's progress (%r)" %
         [l for l in res.stdout.splitlines() if l.startswith("progress")]),
        (worst <= 1, "pvserver renders the builtin image (max |diff| %d <= 1, mean %.4f)" % (worst, mean)),
    ] + ([(zarr_line in res.stdout, "an OME-Zarr read on the server shows the file's channels and colours on "
                                    "the client (%r)" % [l for l in res.stdout.splitlines() if "omezarr" in l])]
         if zarr_line else []):
        print(("PASS: " if ok else "FAIL: ") + msg)
        failures += 0 if ok else 1
    if failures:
        print("images in " + tmp)
        sys.exit(1)
    print("all checks passed")


if __name__ == "__main__":
    main()

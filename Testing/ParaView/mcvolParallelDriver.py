"""What the parallel ParaView tests' drivers share (they run under the
system Python and start pvbatch, under mpiexec or alone, themselves)."""
import argparse
import os
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))


def setup(prefix):
    """The drivers' command line (--pvbatch, --mpiexec, --ranks), the
    environment of their pvbatch runs (this folder on PYTHONPATH; OpenMPI
    allowed to run as root, as CI runs) and a scratch folder whose name
    starts with `prefix`."""
    p = argparse.ArgumentParser()
    p.add_argument("--pvbatch", default="pvbatch")
    p.add_argument("--mpiexec", default="mpiexec")
    p.add_argument("--ranks", type=int, default=2)
    args = p.parse_args()
    env = dict(os.environ)
    env["PYTHONPATH"] = HERE + os.pathsep + env.get("PYTHONPATH", "")
    env.setdefault("OMPI_ALLOW_RUN_AS_ROOT", "1")
    env.setdefault("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
    return args, env, tempfile.mkdtemp(prefix=prefix)

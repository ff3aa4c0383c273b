"""The performance page's scaling tables from the RESULT lines of
mpi_gpus.py (scaling.sh collects them in results.jsonl):

    python3 Benchmarks/gpu/scaling_table.py Benchmarks/results/mpi-scaling-gpu/strong-nyx-4xh200.jsonl
"""
import json
import sys


def main(path):
    rows = [json.loads(line) for line in open(path) if line.strip()]
    for lighting in sorted({r["lighting"] for r in rows}, key=lambda s: s != "none"):
        sel = sorted((r for r in rows if r["lighting"] == lighting), key=lambda r: r["ranks"])
        one = sel[0]
        print("\n%s, %s\n" % (one["label"] or one["dataset"], "unlit" if lighting == "none" else "lit (" + lighting + ")"))
        print("| GPUs | time to %g dB (ms, spp) | speed-up | its trace (ms) | moving frame (ms) | trace / draw (ms) |"
              " still frame of %d spp (ms) | its trace (ms) | samples/s (10^6) | backend memory per rank (MiB) |"
              " ParaView's Outline frame (ms) |" % (35, 16))
        print("|---|---|---|---|---|---|---|---|---|---|---|")
        base = one["time_to_db"]
        for r in sel:
            hit = r["converge"][-1]
            t = r["time_to_db"]
            mem = "/".join("%.0f" % m["backend_mib"] for m in r["memory"])
            outline = "%.2f" % r["outline_ms"] if "outline_ms" in r else "-"
            print("| %d | %s | %s | %.2f | %.2f | %.2f / %.2f | %.2f | %.2f | %.0f | %s | %s |" % (
                r["ranks"], "%.1f (%d)" % (t, r["spp_to_db"]) if t else "not reached",
                "%.2fx" % (base / t) if t and base else "-", hit["trace_ms"],
                r["moving"]["ms"], r["moving"]["trace_ms"], r["moving"]["draw_ms"],
                r["still"]["ms"], r["still"]["trace_ms"], r["still"]["samples_per_s"] / 1e6, mem, outline))


if __name__ == "__main__":
    main(sys.argv[1])

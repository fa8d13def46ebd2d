#!/usr/bin/env python3
"""bench/parallel's tables: medians of the runs in RESULTS (TAG.RUN.wall, and
TAG.RUN.json: the ranks' --stats), TAG = STORE.VIEW.SIZE.RANKS.MODE, and a
paper model of 16 nodes.

The model, per view and mode, from the run with the fewest ranks N > 1
(oversubscription inflates the rest):
  render(16)    = total render work (the sum of the N ranks' render ms)
                  / 16 x (1 + the measured imbalance): triangles split as
                  measured, each node as fast as one of the N ranks;
  select(16)    = sort-last: select(N) (every node selects the whole view);
                  sort-first: select(N) x N / 16 (each node reads only its
                  window's tiles; optimistic: traversal does not shrink);
  composite(16) = bytes / 1.25 GB/s (10 Gbit/s links) + 20 us per message:
                  sort-last: 8 W H (1 - 1/16) + 4 W H / 16 bytes per node
                  (uncompressed), in the messages of the compositor's rounds
                  plus the gather (radix-k:8: 8 x 2, 7 + 1 + 1 messages;
                  binary swap: 2 x 2 x 2 x 2, 4 + 1; direct send: 16, 15 + 1);
                  sort-first: rank 0 receives 4 W H 15/16 bytes in 15 messages.
Usage: parallel_model.py RESULTS CORES
"""
import json
import statistics
import sys
from collections import defaultdict
from pathlib import Path

BANDWIDTH = 1.25e9  # bytes/s
LATENCY = 20e-6  # s per message
NODES = 16


def load(results):
    walls, stats = defaultdict(list), defaultdict(list)
    for f in sorted(Path(results).iterdir()):
        tag, run, kind = f.name.rsplit(".", 2)
        if kind == "wall":
            walls[tag] += [float(x) for x in f.read_text().split()]
        elif kind == "json":
            stats[tag].append(json.loads(f.read_text()))
    return walls, stats


def figures(runs):
    """Medians over runs of the per-frame figures of a parallel still."""
    def med(f):
        return statistics.median(f(r) for r in runs)
    return {
        "select": med(lambda r: max(x["select_ms"] for x in r["ranks"])),
        "render": med(lambda r: max(x["render_ms"] for x in r["ranks"])),
        "render_sum": med(lambda r: sum(x["render_ms"] for x in r["ranks"])),
        "composite": med(lambda r: max(x["composite_ms"] for x in r["ranks"])),
        "triangles": med(lambda r: max(x["triangles"] for x in r["ranks"])),
        "bytes": med(lambda r: sum(x["bytes_sent"] for x in r["ranks"])),
        "imbalance": med(lambda r: r["triangle_imbalance"]),
    }


def shown(mode):  # sort-last-active+binary-swap -> sort-last:active+binary-swap
    mode, plus, composite = mode.partition("+")
    head, _, tail = mode.rpartition("-")
    return f"{head}:{tail}{plus}{composite}"


def messages(composite, nodes):
    """Messages per node of a sort-last compositor (--composite, as
    parallel::composite_rounds factors the nodes: k - 1 per round) plus the
    gather's one."""
    if composite == "direct-send":
        return nodes
    k = 2 if composite == "binary-swap" else int(composite.partition(":")[2] or 8)
    sent, left = 1, nodes
    while left > 1:
        factor = next((f for f in range(min(k, left), 1, -1) if left % f == 0), None)
        factor = factor or next(f for f in range(k + 1, left + 1) if left % f == 0)
        sent, left = sent + factor - 1, left // factor
    return sent


def model(mode, n, f, width, height):
    render = f["render_sum"] / NODES * (1 + f["imbalance"])
    pixels = width * height
    if mode.startswith("sort-last"):
        select = f["select"]
        sent = 8 * pixels * (1 - 1 / NODES) + 4 * pixels / NODES
        count = messages(mode.partition("+")[2] or "radix-k", NODES)
        composite = 1e3 * (sent / BANDWIDTH + count * LATENCY)
    else:
        select = f["select"] * n / NODES
        composite = 1e3 * (4 * pixels * (NODES - 1) / NODES / BANDWIDTH + (NODES - 1) * LATENCY)
    return select, render, composite


def main():
    results, cores = sys.argv[1], int(sys.argv[2])
    walls, stats = load(results)
    groups = defaultdict(dict)
    for tag in walls:
        store, view, size, n, mode = tag.split(".")
        groups[(store, view, size)][(int(n), mode)] = tag
    models = []
    for (store, view, size), runs in groups.items():
        width, height = (int(v) for v in size.split("x"))
        print(f"\n{store}, {view} view, {size}:\n")
        print("| ranks | mode | wall s | vs one process | select ms | render ms | composite ms "
              "| triangles (max rank) | imbalance | bytes/frame |")
        print("|---|---|---|---|---|---|---|---|---|---|")
        one = statistics.median(walls[runs[(1, "one")]])
        print(f"| 1 | one process | {one:.2f} | 1.00× | | | | | | |")
        fewest = {}
        for (n, mode), tag in sorted(runs.items()):
            if mode == "one":
                continue
            wall = statistics.median(walls[tag])
            f = figures(stats[tag])
            over = " (oversubscribed)" if n > cores else ""
            print(f"| {n}{over} | {shown(mode)} | {wall:.2f} | {one / wall:.2f}× "
                  f"| {f['select']:.0f} | {f['render']:.0f} | {f['composite']:.0f} "
                  f"| {f['triangles']:,.0f} | {100 * f['imbalance']:.1f} % "
                  f"| {f['bytes'] / 1e6:.1f} MB |")
            if mode not in fewest or n < fewest[mode][0]:
                fewest[mode] = (n, f)
        for mode, (n, f) in sorted(fewest.items()):
            s, r, c = model(mode, n, f, width, height)
            models.append(f"| {store}, {view}, {size} | {shown(mode)} (from {n} ranks) "
                          f"| {s:.0f} | {r:.0f} | {c:.1f} | {s + r + c:.0f} |")
    print(f"\nPaper model of {NODES} nodes (bench/parallel_model.py: render work split as measured, "
          "10 Gbit/s links, 20 µs per message):\n")
    print("| view | mode | select ms | render ms | composite ms | frame ms |")
    print("|---|---|---|---|---|---|")
    print("\n".join(models))


if __name__ == "__main__":
    main()

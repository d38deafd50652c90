"""Per-variation relayout time for models of about 100, 500, 1300 and 12000 terminal regions (bao2013 Table II).

The large models are synthesised towers in the spirit of the paper's skyscraper (Fig. 11): nested grids of floors,
window bays and panes, symmetric floors (replicated), repeatable floors and bays, two independently relayouted bay instances,
bays aligned across floors and same-size floors. The shipped models are timed at their input size too. Each
model is relayouted at its input size for several seeds, the towers also at a larger target (their variations at
the input size choose fewer, wider bays, so outputs have fewer terminals than the input); the input and median
output terminal counts and the median and maximum time per variation are printed, with the paper's figures
(2.67 GHz i7) for comparison.

    python benchmarks/relayout_variations.py [--runs 15]
"""
from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

from citygen_relayout import load_model, parse_model, relayout, validate

RULESETS = Path(__file__).resolve().parents[1] / "rulesets"
PAPER = "Table II: 16-262 ms for 93-1323 terminals (27 ms at 93, 103 ms at 1323), 3715 ms at 12016"


def tower(floors: int, bays: int, panes: int) -> str:
    """A tower model: Base, ``floors`` floors of ``bays`` bays of ``panes`` panes, Crown."""
    fh, bw, pw = 4.0, 0.6 + panes * 0.9, 0.9
    width = 1.0 + bays * (bw + 1.0)
    height = 5.0 + floors * fh + 3.0
    floor_kids = " ".join(["Pier:1"] + ["Bay:%g Pier:1" % bw] * bays)
    pane_kids = " ".join(["Mul:0.1"] + ["Pane:%g Mul:0.1" % (pw - 0.1 + 0.1 / panes)] * panes)
    row_w = 0.1 + panes * (pw - 0.1 + 0.1 / panes + 0.1)
    bay_pad = (bw - row_w) / 2
    return f"""model tower_{floors}x{bays}x{panes}
root Tower {width:g} {height:g}
split Tower y Base:5 {" ".join(["Floor:4"] * floors)} Crown:3
split Base x {" ".join(["Pier:1"] + ["Entry:%g Pier:1" % bw] * bays)}
split Entry y Door:3 Over:2
split Floor x {floor_kids}
split Bay y Spandrel:0.9 WinRow:2.4 Lintel:0.7
split WinRow x Side:{bay_pad:g} Glazing:{row_w:g} Side:{bay_pad:g}
split Glazing x {pane_kids}
split Pane y Frame:0.1 Glass:2.2 Frame:0.1
terminal Pier pillar
terminal Door door
terminal Over wall
terminal Spandrel wall
terminal Lintel wall
terminal Side wall
terminal Mul frame
terminal Frame frame
terminal Glass window depth -0.2
terminal Crown cornice depth 0.3
size Floor 3.2..4.8
size Pier 0.6..2.5
size Bay 2..{bw * 1.6:g}
size Entry 2..{bw * 1.6:g}
size Pane 0.6..1.4
size Side 0.05..1.5
repeat Tower : Base Floor+ Crown
repeat Floor : Pier (Bay Pier)+
repeat Base : Pier (Entry Pier)+
repeat Glazing : Mul (Pane Mul)+
freq Base Entry 1..{bays}
symmetric Floor
instances Floor Bay 1..2
samesize Floor = Floor
align Bay.center = Bay.center
"""


def bench(name: str, model, width: float, height: float, runs: int) -> None:
    times, terms, bad = [], [], 0
    relayout(model, width, height, seed=10_000)  # compile the model's tables outside the timing
    for seed in range(runs):
        t = time.perf_counter()
        result = relayout(model, width, height, seed=seed)
        times.append(time.perf_counter() - t)
        if not result.success:
            bad += 1
            continue
        terms.append(len(result.layout.terminals()))
        if seed < 3 and validate(result.layout, model):
            bad += 1
    med = statistics.median(times) * 1000
    print(f"{name:28s} {model.terminal_count():6d} {int(statistics.median(terms)) if terms else 0:8d} "
          f"{med:10.1f} {max(times) * 1000:9.1f} {bad:5d}")


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--runs", type=int, default=15)
    args = parser.parse_args()
    print(PAPER)
    print(f"{'model':28s} {'input':>6s} {'output':>8s} {'median ms':>10s} {'max ms':>9s} {'fail':>5s}")
    for name in ("fig7_walkthrough", "cmp_b0035", "townhouse"):
        model = load_model(RULESETS / f"{name}.relayout")
        bench(name, model, model.width, model.height, args.runs)
    for floors, bays, panes in ((3, 2, 2), (8, 4, 2), (12, 6, 3), (38, 12, 5)):
        model = parse_model(tower(floors, bays, panes), "tower.relayout")
        runs = args.runs if floors < 30 else max(5, args.runs // 3)
        bench(model.name, model, model.width, model.height, runs)
        # a larger target, so that the outputs themselves reach about the input's terminal count
        bench(model.name + " x1.6,1.4", model, model.width * 1.6, model.height * 1.4, runs)


if __name__ == "__main__":
    main()

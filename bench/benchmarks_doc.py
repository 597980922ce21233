#!/usr/bin/env python3
"""Writes docs/benchmarks.md from the records alone: bench/results/NAME.json (one per peer
comparison, written by bench/peers/compare.py; the other records of bench/*.py) and the
charts' captions docs/charts/NAME.md with their CSVs (written by `cgnodes sweep`). Every figure
in the page is copied from a record, which is named beside it with its commit and date.

It also fills, in the other docs/*.md, every block between a line
`<!-- record: NAME -->` and the next `<!-- end record -->` with the ratio table of
bench/results/NAME.json (and nothing else in those files), so a subject's doc quotes the same
record.

    python3 bench/benchmarks_doc.py      # what `bench/run_all --docs` runs
"""
import json
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, os.path.join(HERE, "peers"))
from compare import COMPARISONS  # noqa: E402

RESULTS = os.path.join(ROOT, "bench", "results")
# The chart (docs/charts/NAME.svg, drawn by `bench/run_all NAME`) that shows a comparison's
# peer as a series.
CHART = {"arap_libigl": "arap_iterations", "mitsuba_scalar": "trace_cornell_spp",
         "mitsuba_llvm": "trace_cornell_spp", "splishsplash": "sph_dam_break"}


def load(name):
    try:
        with open(os.path.join(RESULTS, name + ".json")) as f:
            return json.load(f)
    except (OSError, ValueError):
        return None


def num(x):
    if x is None:
        return "-"
    if isinstance(x, bool):
        return "yes" if x else "no"
    if isinstance(x, int):
        return f"{x:,}"
    if isinstance(x, float):
        if x == 0:
            return "0"
        a = abs(x)
        if a >= 100:
            return f"{x:,.0f}"
        if a >= 1:
            return f"{x:.2f}"
        if a >= 1e-3:
            return f"{x:.4g}"
        return f"{x:.1e}"
    return str(x)


def accuracy(d):
    return "; ".join(f"{k.replace('_', ' ')} {num(v)}" for k, v in (d or {}).items()) or "-"


def stamp(rec):
    m = rec.get("machine", {})
    rounds = rec.get("rounds")
    load = m.get("load_average")
    return (f"record `bench/results/{rec['benchmark']}.json`: commit {rec.get('commit', '?')}, "
            f"{rec.get('date', '?')}, {m.get('cores', '?')} cores ({m.get('model') or m.get('cpu', '?')}"
            + (f", load average {load[0]} at the end" if load else "") + ")"
            + (f", {rounds} alternated round{'s' if rounds != 1 else ''}" if rounds else ""))


def rfmt(x):
    return f"{x:.2f}" if x >= 0.1 else f"{x:.2g}"


def ratio(c):
    """The ratio of the medians, with the range of the rounds' own ratios."""
    if c.get("ratio") is None:
        return "-"
    r = rfmt(c["ratio"])
    rr = c.get("round_ratios") or []
    if len(rr) > 1:
        r += f" ({rfmt(min(rr))}-{rfmt(max(rr))})"
    return r


def table(rec, out):
    cases = rec.get("cases", [])
    # Records whose peer time leaves out the scene set-up also give ours without it.
    render = any(c.get("render_ratio") is not None for c in cases)
    extra = " ours without scene preparation: ms, ratio |" if render else ""
    out.append("| case | cgnodes ms | peer ms | ratio cgnodes / peer (rounds) |" + extra + " accuracy |")
    out.append("|---|---|---|---|" + ("---|" if render else "") + "---|")
    for c in cases:
        col = ""
        if render:
            rr = c.get("render_ratio")
            col = f" {num(c.get('median_ours_render_ms'))}, {rfmt(rr) if rr is not None else '-'} |"
        out.append(f"| {c['case']} | {num(c.get('median_ours_ms'))} | {num(c.get('median_peer_ms'))} | "
                   f"{ratio(c)} |{col} {accuracy(c.get('accuracy'))} |")
    out.append("")


def comparison(name, fn, out):
    rec = load(name)
    doc = " ".join(fn.__doc__.split())
    out.append(f"### {name}\n")
    if rec is None:
        out.append(f"{doc}\n\n**Not measured**: no record yet (`bench/run_all --peers --only {name}`).\n")
        return
    out.append(f"{rec.get('method', doc)} Peer: {rec.get('peer') or '?'}. Threads: {rec.get('threads', '?')}. "
               f"Timed: ours {rec.get('ours', '?')}; peer {rec.get('peer_side', '?')}.")
    out.append(f"Rerun: `{rec['command']}`; {stamp(rec)}.\n")
    if rec.get("status", "measured") != "measured":
        reason = (rec.get("reason") or "").splitlines()[0]
        out.append(f"**Not measured** in the last run: {reason}\n")
        return
    if rec.get("smoke"):
        out.append("This record is from a `--smoke` run (small sizes, one round).\n")
    table(rec, out)
    chart = CHART.get(name)
    if chart:
        out.append(f"![{name}: the peer's series in docs/charts/{chart}.svg](charts/{chart}.svg)")
        out.append(f"The chart is the sweep `bench/run_all {chart}` (its own run, data and caption "
                   f"under Charts below), not this record.\n")


def summary(out):
    out.append("| comparison | peer | ratio cgnodes / peer (median per case) | record date |")
    out.append("|---|---|---|---|")
    for name in COMPARISONS:
        rec = load(name)
        if rec is None or rec.get("status", "measured") != "measured":
            out.append(f"| [{name}](#{name}) | {rec.get('peer', '') if rec else ''} | not measured | "
                       f"{rec.get('date', '') if rec else ''} |")
            continue
        ratios = [c["ratio"] for c in rec.get("cases", []) if c.get("ratio") is not None]
        r = ", ".join(rfmt(x) for x in ratios) if ratios else "accuracy only"
        out.append(f"| [{name}](#{name}) | {rec.get('peer') or ''} | {r} | {rec.get('date', '')} |")
    out.append("")


def charts(out):
    folder = os.path.join(ROOT, "docs", "charts")
    for md in sorted(f for f in os.listdir(folder) if f.endswith(".md")):
        name = md[:-3]
        with open(os.path.join(folder, md)) as f:
            out.append(f.read().rstrip() + "\n")
        csvs = sorted(f for f in os.listdir(folder) if f.startswith(name) and f.endswith(".csv"))
        if csvs:
            out.append("Data: " + ", ".join(f"[{c}](charts/{c})" for c in csvs)
                       + f" (written by `bench/run_all {name}`).\n")
        rec = load("chart_" + name)
        if rec and rec.get("status") == "not measured":
            out.append(f"**Not measured** in the last run of `bench/run_all {name}` ({rec.get('date')}): "
                       f"{(rec.get('reason') or '').splitlines()[0]}; the chart and data above are from "
                       "the run before it.\n")


def others(out):
    known = set(COMPARISONS)
    rows = []
    for f in sorted(os.listdir(RESULTS)):
        name = f[:-5]
        if not f.endswith(".json") or name in known or name.startswith("chart_"):
            continue
        rec = load(name)
        if rec is None:
            continue
        rows.append(f"| `bench/results/{f}` | `{rec.get('command', '?')}` | {rec.get('commit', '?')} | "
                    f"{rec.get('date', '?')} |")
    if rows:
        out.append("## Other records\n")
        out.append("Cited by the documentation of their subject (docs/report.md, docs/parameterization.md, "
                   "docs/development.md).\n")
        out.append("| record | command | commit | date |")
        out.append("|---|---|---|---|")
        out.extend(rows)
        out.append("")


def fill_blocks():
    """Fills the `<!-- record: NAME -->` blocks of the other docs (see the module doc)."""
    import re
    block = re.compile(r"(<!-- record: ([a-z0-9_]+) -->\n)(.*?)(<!-- end record -->)", re.S)
    folder = os.path.join(ROOT, "docs")

    def fill(m):
        rec = load(m.group(2))
        out = []
        if rec is None or rec.get("status", "measured") != "measured":
            out.append(f"Not measured (`bench/run_all --peers --only {m.group(2)}`).\n")
        else:
            out.append(f"Peer: {rec.get('peer') or '?'}; rerun: `{rec['command']}`; {stamp(rec)}.\n")
            table(rec, out)
        return m.group(1) + "\n".join(out) + m.group(4)

    for md in sorted(os.listdir(folder)):
        if not md.endswith(".md") or md == "benchmarks.md":
            continue
        path = os.path.join(folder, md)
        text = open(path).read()
        new = block.sub(fill, text)
        if new != text:
            with open(path, "w") as f:
                f.write(new)
            print(f"filled the record blocks of docs/{md}")


def main():
    out = [
        "# Benchmarks and charts",
        "",
        "Generated by `bench/run_all --docs` (`bench/benchmarks_doc.py`) from the records in",
        "`bench/results/` and the charts' data in `docs/charts/`; edit those, not this page. Every",
        "figure below is copied from the record named beside it, with the commit and date it was",
        "measured at. Speed is given as the ratio cgnodes / peer of times measured in the same run,",
        "ours and the peer alternated round by round on the same machine; absolute milliseconds",
        "depend on the machine and its load.",
        "",
        "- `bench/run_all --peers` reruns every comparison against a peer library (it installs the",
        "  peers into `target/peers-venv` with pip) and rewrites its record; `--only NAME` one,",
        "  `--rounds N` the rounds, `--smoke` each at a small size once (what CI runs),",
        "  `--skip-missing` records a missing peer as not measured instead of failing.",
        "- `bench/run_all NAME` reruns a chart's sweep (`bench/sweeps/NAME.json`, then",
        "  `bench/sweeps/NAME.sh`); `bench/run_all` all of them.",
        "",
        "## Against peer libraries",
        "",
        "In each table the milliseconds are medians over the rounds (every round's times are in the",
        "record), the ratio is that of the medians, and in brackets the lowest and highest ratio",
        "within one round; below 1 cgnodes is faster. The summary gives each case's ratio in the",
        "order of its table.",
        "",
    ]
    summary(out)
    for name, fn in COMPARISONS.items():
        comparison(name, fn, out)
    out.append("## Charts\n")
    out.append("Each chart is drawn by `cgnodes sweep` (and `cgnodes chart` for a peer's series) "
               "from the CSV named below it.\n")
    charts(out)
    others(out)
    text = "\n".join(out).rstrip() + "\n"
    path = os.path.join(ROOT, "docs", "benchmarks.md")
    with open(path, "w") as f:
        f.write(text)
    print(f"wrote docs/benchmarks.md ({text.count(chr(10))} lines)")
    fill_blocks()


if __name__ == "__main__":
    main()

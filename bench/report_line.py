#!/usr/bin/python3
"""One markdown table row per hocad run, from its JSON report (--json).

Used by bench/corpus.sh and bench/orders_cost.sh; Python's standard library
only. Subcommands:

  header                      the header of the `run` table
  run   --model M --order P --exit RC --wall S [--rss-kb K] [--json F]
        [--stderr F] [--cad F] [--timeout S] [--why F] [--startup S]
                              the row of one `hocad mesh` run; exit status 0
                              if it meets the bounds, 1 if not (the reason
                              also goes to --why)
  hard-header                 the header of the `hard` table
  hard  --model M --exit RC [--stderr F] [--timeout S] [--why F]
                              the row of a model gmsh cannot mesh: expected
                              a clean non-zero exit with a message, never a
                              signal or a timeout
  sweep --json F              "elements iterations seconds" of the first
                              optimisation (for orders_cost.sh)

The bounds of a run (issue 3, then 32): exit 0; 0 tangled (the report's
count is the exact test's, as hoc_mesh_measure counts); final min q >= 0.9 x
the linear mesh's min q, unless hocad's finding says every element below
that bound has a corner at a CAD cusp or crosses a pinch of its face (when
only some do, the others must meet it); final mean q >= linear mean q - 0.02; with --cad (the
output of `hocad quality` on the written mesh), the farthest node within
1e-9 of the model's size from the CAD; at order 3, at most 5 s per 10^4
elements of hocad's own time (the wall time less the CAD import and gmsh's
linear meshing, which the report times, and less --startup, the seconds a
process takes to load gmsh's and OpenCASCADE's shared libraries). The
report's linear stage is the last one (after a remeshing the stages are
those of the last attempt); the final stage is the last.
"""
import argparse
import json
import re
import signal
import sys

POOR = 0.9        # min q bound: this fraction of the linear mesh's min q
MEAN_DROP = 0.02  # mean q bound: at most this below the linear mesh's mean q
ON_CAD = 1e-9     # farthest node from the CAD, relative to the model's size
SLOW = 5.0        # at order 3: at most this many seconds of hocad's own time per 10^4 elements

RUN_COLUMNS = ["model", "p", "elements", "tangled raised", "tangled final",
               "min q linear -> final", "mean q linear -> final", "bounds",
               "wall s", "CAD + linear s", "hocad s / 1e4 el", "peak MB", "exit"]
HARD_COLUMNS = ["model (hard/)", "exit", "message", "verdict"]


def table_header(columns):
    print("| " + " | ".join(columns) + " |")
    print("|" + "|".join("---" for _ in columns) + "|")


def row(cells):
    print("| " + " | ".join(str(c).replace("|", "/") for c in cells) + " |")


def read_text(path):
    if not path:
        return ""
    try:
        with open(path, errors="replace") as f:
            return f.read()
    except OSError:
        return ""


def first_message(text, width=160):
    """The first error line of hocad's stderr, else its first line, without
    the program's name, cut to `width` characters."""
    lines = [l.strip() for l in text.splitlines() if l.strip()]
    errors = [l for l in lines if ": error: " in l]
    msg = (errors or lines or [""])[0]
    msg = re.sub(r"^hocad: (error: |warning: |note: )?", "", msg)
    return msg if len(msg) <= width else msg[:width - 3] + "..."


def exit_meaning(rc, timeout):
    """What an exit code says: None for 0, else a short phrase."""
    if rc == 0:
        return None
    if rc == 124:
        return "timeout after %s s" % (timeout or "?")
    if rc > 128:
        try:
            name = signal.Signals(rc - 128).name
        except ValueError:
            name = "signal %d" % (rc - 128)
        return "killed by %s" % name
    return "exit %d" % rc


def stage_list(report):
    return report.get("stages", [])


def last_stage(stages, name):
    found = [s for s in stages if s.get("name") == name]
    return found[-1] if found else None


def explained_check(stderr, bound):
    """Which of hocad's notes on the elements below the bound explain them
    ("cusps", "pinches", "cusps and pinches"), or None: all of them at a cusp
    or across a pinch, or the elements neither meet the bound."""
    low = r"(\d+) of the (\d+) element\(s\) below 0\.9 x the linear mesh's min q"
    cusp = re.search(low + r" \([^)]*\) have a corner at a cusp.*?the elements at no cusp "
                     r"have min q ([-0-9.e+]+)", stderr, re.S)
    pinch = re.search(low + r" \([^)]*\) cross a pinch.*?the elements at no cusp and across "
                      r"no pinch have min q ([-0-9.e+]+)", stderr, re.S)
    if pinch:
        n_low, rest = int(pinch.group(2)), float(pinch.group(3))
        at = int(pinch.group(1)) + (int(cusp.group(1)) if cusp else 0)
        ok = at == n_low or rest >= bound
        return ("cusps and pinches" if cusp else "pinches") if ok else None
    if not cusp:
        return None
    at_cusp, n_low, rest = int(cusp.group(1)), int(cusp.group(2)), float(cusp.group(3))
    return "cusps" if at_cusp == n_low or rest >= bound else None


def cad_distance(text):
    """Relative distance of the farthest node from `hocad quality`'s first line."""
    m = re.search(r"farthest node (\S+) from the CAD \((\S+) of the model's size\)", text)
    return float(m.group(2)) if m else None


def cmd_run(a):
    reasons, cells = [], None
    report = None
    if a.json:
        try:
            with open(a.json) as f:
                report = json.load(f)
        except (OSError, ValueError):
            report = None
    stderr = read_text(a.stderr)
    bad_exit = exit_meaning(a.exit, a.timeout)
    if bad_exit:
        # exit 5 (tangled) is said by the tangled count below
        msg = first_message(stderr) if a.exit not in (5, 124) and a.exit <= 128 else ""
        reasons.append(bad_exit + (": " + msg if msg else ""))
    wall = "%.1f" % a.wall
    rss = "%.0f" % (a.rss_kb / 1024) if a.rss_kb else "-"
    stages = stage_list(report) if report else []
    lin, raised = last_stage(stages, "linear"), last_stage(stages, "high-order")
    if stages and lin:
        fin = stages[-1]
        ne = fin["elements"]
        bound = POOR * lin["min"]
        if fin["tangled"] > 0:
            reasons.append("%d tangled" % fin["tangled"])
        if fin["min"] < bound:
            why = explained_check(stderr, bound)
            if why:
                reasons_ok = "min q at %s (hocad's note)" % why
            else:
                reasons.append("min q %.4f < 0.9 x %.4f" % (fin["min"], lin["min"]))
                reasons_ok = None
        else:
            reasons_ok = None
        if fin["mean"] < lin["mean"] - MEAN_DROP:
            reasons.append("mean q %.4f < %.4f - 0.02" % (fin["mean"], lin["mean"]))
        if a.cad:
            d = cad_distance(read_text(a.cad))
            if d is None:
                reasons.append("CAD check failed: " + first_message(read_text(a.cad)))
            elif not d <= ON_CAD:
                reasons.append("node %.2g of the size off the CAD" % d)
        # gmsh's part: loading its libraries, the import and the linear
        # meshing (every linear stage)
        gmsh_s = a.startup + report.get("model_seconds", 0) + sum(
            st.get("seconds", 0) for st in stages if st.get("name") == "linear")
        rate = max(a.wall - gmsh_s, 0) / ne * 1e4 if ne else 0
        if a.order == 3 and rate > SLOW:
            reasons.append("%.1f s / 1e4 el at order 3 > %g" % (rate, SLOW))
        extra = []
        if report.get("remeshings"):
            extra.append("%d remeshed" % report["remeshings"])
        if report.get("refinements"):
            extra.append("%d refined" % report["refinements"])
        verdict = "; ".join(reasons) if reasons else "met"
        if not reasons and reasons_ok:
            verdict = "met, " + reasons_ok
        if extra:
            verdict += " (" + ", ".join(extra) + ")"
        cells = [a.model, a.order, ne, raised["tangled"] if raised else "-", fin["tangled"],
                 "%.4f -> %.4f" % (lin["min"], fin["min"]),
                 "%.4f -> %.4f" % (lin["mean"], fin["mean"]),
                 verdict, wall, "%.1f" % gmsh_s, "%.2f" % rate if ne else "-", rss, a.exit]
    else:
        if not reasons:
            reasons.append("no report written")
        verdict = "; ".join(reasons)
        cells = [a.model, a.order, "-", "-", "-", "-", "-", verdict, wall, "-", "-", rss, a.exit]
    row(cells)
    if a.why:
        with open(a.why, "w") as f:
            f.write(verdict if reasons else "")
    return 1 if reasons else 0


def cmd_hard(a):
    stderr = read_text(a.stderr)
    msg = first_message(stderr)
    if a.exit == 0:
        verdict = "exit 0: expected a refusal"
    elif a.exit == 124:
        verdict = "timeout after %s s" % (a.timeout or "?")
    elif a.exit > 128:
        verdict = exit_meaning(a.exit, a.timeout)
    elif not msg:
        verdict = "no message"
    else:
        verdict = "ok"
    row([a.model, a.exit, msg or "-", verdict])
    if a.why:
        with open(a.why, "w") as f:
            f.write("" if verdict == "ok" else verdict)
    return 0 if verdict == "ok" else 1


def cmd_sweep(a):
    with open(a.json) as f:
        report = json.load(f)
    opt = [s for s in stage_list(report) if s.get("name") == "optimized"]
    if not opt:
        print("no optimized stage in %s" % a.json, file=sys.stderr)
        return 1
    s = opt[0]
    print(s["elements"], s.get("iterations", 0), s["seconds"], s["tangled"],
          report.get("refinements", 0), report.get("remeshings", 0))
    return 0


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    sub = p.add_subparsers(dest="cmd", required=True)
    sub.add_parser("header")
    sub.add_parser("hard-header")
    r = sub.add_parser("run")
    r.add_argument("--model", required=True)
    r.add_argument("--order", required=True, type=int)
    r.add_argument("--exit", required=True, type=int)
    r.add_argument("--wall", required=True, type=float)
    r.add_argument("--rss-kb", type=float, default=0)
    r.add_argument("--json")
    r.add_argument("--stderr")
    r.add_argument("--cad")
    r.add_argument("--timeout")
    r.add_argument("--why")
    r.add_argument("--startup", type=float, default=0)
    h = sub.add_parser("hard")
    h.add_argument("--model", required=True)
    h.add_argument("--exit", required=True, type=int)
    h.add_argument("--stderr")
    h.add_argument("--timeout")
    h.add_argument("--why")
    s = sub.add_parser("sweep")
    s.add_argument("--json", required=True)
    a = p.parse_args()
    if a.cmd == "header":
        table_header(RUN_COLUMNS)
        return 0
    if a.cmd == "hard-header":
        table_header(HARD_COLUMNS)
        return 0
    return {"run": cmd_run, "hard": cmd_hard, "sweep": cmd_sweep}[a.cmd](a)


if __name__ == "__main__":
    sys.exit(main())

"""``README.md`` of the study folder, rebuilt from every ``<study>.json`` in it."""

from __future__ import annotations

import json
import math
from pathlib import Path

from flexnet_fe.study.common import HEADLINE_TOLERANCE

ORDER = ("deploy", "collide", "shell", "flight", "stability", "simplify", "throughput")


def _f(x, pct: bool = False) -> str:
    if isinstance(x, bool) or x is None:
        return "—" if x is None else ("yes" if x else "no")
    if isinstance(x, (int, float)):
        if not math.isfinite(x):
            return "—"
        return f"{100 * x:.3g} %" if pct else f"{x:.4g}"
    return str(x)


def _table(rows: list[dict], cols: list[str], pct: set[str] = frozenset()) -> list[str]:
    out = ["| " + " | ".join(cols) + " |", "|" + "---|" * len(cols)]
    for r in rows:
        out.append("| " + " | ".join(_f(r.get(c), c in pct) for c in cols) + " |")
    return out


def _machine(rec: dict) -> str:
    m, e = rec["machine_start"], rec.get("machine_end", rec["machine_start"])
    return (f"*{rec['name']}: {'quick' if rec['quick'] else 'full'} study, {m['date_utc']}, {m['cpu_model']}, "
            f"{m['cores']} cores, load average (1/5/15 min) {m['loadavg']} at start, {e['loadavg']} at end; "
            f"{rec['wall_s']:.0f} s wall, {rec['cpu_s']:.0f} s CPU.*")


def _accuracy(rec: dict) -> list[str]:
    name, rows, v = rec["name"], rec["rows"], rec.get("verdict", {})
    errs = [k for k in rows[0] if k.startswith("err_")] if rows else []
    shown = [k for k in rows[0] if k.endswith("_own_err")] if rows else []  # reported, not in the verdict
    out = [f"### {name}", "", _machine(rec), ""]
    out += [f"- {n}" for n in rec["notes"]]
    if v.get("default_on_front") is not None:
        ok = v["default_on_front"] and v["default_within"]
        out += ["", f"**Verdict: the shipped default is {'on' if v['default_on_front'] else 'OFF'} the Pareto "
                    f"front and {'within' if v['default_within'] else 'NOT within'} "
                    f"{HEADLINE_TOLERANCE:.0%} of the reference** (worst headline error "
                    f"{_f(v['default_worst_error'], True)}; cheapest point within {HEADLINE_TOLERANCE:.0%}: "
                    f"{v['cheapest_within'] or 'none'})." + ("" if ok else " The default does not meet the issue's "
                                                                          "bar here; see the table.")]
    out += [""] + _table(rows, ["knob", "value", "cpu_s", "wall_s", *errs, *shown, "on_front", "status"],
                         set(errs) | set(shown))
    excluded = [f"- excluded from the front: {r['knob']} = {r['value']}: {r['excluded']}"
                for r in rows if r.get("excluded")]
    out += [""] + excluded if excluded else []
    out += ["", f"![{name}: accuracy against cost]({name}_accuracy.png)", ""]
    return out


def _stability(rec: dict) -> list[str]:
    rows = rec["rows"]
    out = ["## Stability maps", "", _machine(rec), ""] + [f"- {n}" for n in rec["notes"]] + [""]
    out += ["| map | points | ok | flagged | stopped by guard | wrong numbers escaped |", "|---|---|---|---|---|---|"]
    for m in dict.fromkeys(r["map"] for r in rows):
        rs = [r for r in rows if r["map"] == m]
        n = lambda s: sum(r["status"] == s for r in rs)  # noqa: E731
        out.append(f"| {m} | {len(rs)} | {n('ok')} | {n('flagged')} | {n('stopped')} | "
                   f"{sum(r['escaped'] for r in rs)} |")
    out += ["", "![dt against energy growth](stability_dt.png)", "",
            "![contact stiffness × dt × speed](stability_contact.png)", "",
            "![damping models: restitution achieved](stability_damping.png)", ""]
    esc = [r for r in rows if r["escaped"]]
    if esc:
        out += [f"### Wrong numbers that escaped ({len(esc)} points: bugs or unguarded limits)", ""]
        keys = [k for k in ("map", "model", "restitution_requested", "restitution_achieved", "impact_speed_mps",
                            "stiffness", "pass_through_fraction", "penetration_ratio", "dt_over_dt_crit",
                            "dt_scale", "energy_growth", "err_headline") if any(k in r for r in esc)]
        out += _table(esc, keys) + [""]
    return out


def _simplify(rec: dict) -> list[str]:
    out = ["## Simplifications: with and without", "", _machine(rec), ""] + [f"- {n}" for n in rec["notes"]] + [""]
    if rec["rows"]:
        out += _table(rec["rows"], ["simplification", "without", "stage", "headline", "with_value",
                                    "without_value", "difference_rel", "cost_with_s", "cost_without_s", "matters"],
                      {"difference_rel"})
        flagged = [r for r in rec["rows"] if r["matters"]]
        out += ["", f"**{len(flagged)} difference(s) above {HEADLINE_TOLERANCE:.0%}**" +
                (": " + "; ".join(sorted({f"{r['simplification']} ({r['stage']})" for r in flagged})) if flagged
                 else "."), ""]
    return out


def _throughput(rec: dict) -> list[str]:
    out = ["## Throughput and scaling", "", _machine(rec), ""] + [f"- {n}" for n in rec["notes"]] + [""]
    for kind, title in (("net_kernel", "Net kernel against plain numpy (one core)"),
                        ("stream_triad", "STREAM triad (numba, one core, thread CPU time)"),
                        ("shell_bandwidth", "Shell step: bytes moved per step (counted from the kernel's "
                                            "arrays) over its time → effective bandwidth and fraction of the triad"),
                        ("shell_dof_step", "Shell: CPU ns per DOF-step in the shell study's runs "
                                           "(computed from the shell record on this page: its code and date)"),
                        ("scaling", "Cost against problem size (log-log slope; from the accuracy records on "
                                    "this page: their code and dates)"),
                        ("end_to_end", "Default case end to end, by stage: wall [s] and its split (parts timed "
                                       "at their entry functions: s_kernel = the compiled time loop; s_* the "
                                       "parts outside it; s_other = the rest)"),
                        ("mpi", "Shell stage of the default case: 1 against 2 MPI ranks")):
        rs = [r for r in rec["rows"] if r["kind"] == kind]
        if rs:
            cols: list[str] = []
            for r in rs:
                cols += [k for k in r if k != "kind" and k not in cols]
            out += [f"### {title}", ""] + _table(rs, cols) + [""]
    return out


def draw_charts(out: Path, recs: dict) -> None:
    """The PNGs, from the rows stored in ``<study>.json`` (so a chart can be redrawn without a re-run)."""
    from flexnet_fe.study import plots

    for n in ("deploy", "collide", "shell", "flight"):
        if n in recs and recs[n]["rows"]:
            plots.accuracy_chart(n, recs[n]["rows"], out / f"{n}_accuracy.png",
                                 f"{n}: accuracy against cost ({'quick' if recs[n]['quick'] else 'full'} study)")
    if "stability" in recs:
        rows = recs["stability"]["rows"]
        plots.dt_map_chart(rows, out / "stability_dt.png")
        plots.contact_chart(rows, out / "stability_contact.png")
        plots.damping_chart(rows, out / "stability_damping.png")


def write_page(out: Path) -> Path:
    """Redraw the charts and rewrite ``out/README.md`` from every ``<study>.json`` in ``out``."""
    out = Path(out)
    recs = {n: json.loads((out / f"{n}.json").read_text()) for n in ORDER if (out / f"{n}.json").is_file()}
    draw_charts(out, recs)
    lines = ["# flexnet study: accuracy against cost, stability, simplifications, throughput", "",
             "Written by `flexnet study STAGE|all [--quick] [--out DIR]` (flexnet_fe/study/, issue 15): every "
             "figure below was measured side by side in one run on the machine named with it (the machine is "
             "shared: absolute times vary with the load shown; compare within a table). Errors are relative "
             "to the fine reference computed in the same run (every knob at its finest), CPU time is the "
             "process CPU time of the stage call (all threads). Data: `<study>.csv` beside this page.", ""]
    provenance = out / "PROVENANCE.md"  # hand-written: which tree and defaults the records describe
    if provenance.is_file():
        lines += ["## Which code these numbers describe", "", provenance.read_text().strip(), ""]
    acc = [n for n in ("deploy", "collide", "shell", "flight") if n in recs]
    if acc:
        lines += ["## Accuracy against cost", "", "| stage | default on the Pareto front | default within 2 % | "
                  "worst headline error of the default |", "|---|---|---|---|"]
        for n in acc:
            v = recs[n].get("verdict", {})
            lines.append(f"| {n} | {_f(v.get('default_on_front'))} | {_f(v.get('default_within'))} | "
                         f"{_f(v.get('default_worst_error'), True)} |")
        lines.append("")
        for n in acc:
            lines += _accuracy(recs[n])
    if "stability" in recs:
        lines += _stability(recs["stability"])
    if "simplify" in recs:
        lines += _simplify(recs["simplify"])
    if "throughput" in recs:
        lines += _throughput(recs["throughput"])
    page = out / "README.md"
    page.write_text("\n".join(lines) + "\n")
    return page

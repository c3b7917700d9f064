"""The verdict at the top of the report: fin margins of safety, the missile's response, the
flight outcome and every warning any stage logged (issue 12 item 1).

Everything here is read from the run directory (``summary.json``, ``status.json``,
``resolved.json``); nothing is recomputed from physics. The only arithmetic is the margin of
safety and the Δv fallback, both stated on the report.

Margin of safety (static strength, as in a stress report):

    MS = σ_allow / σ − 1        PASS when MS ≥ 0

with σ the fin's peak von Mises stress (a ductile fin yields on von Mises; its strike envelope,
``strike_envelope_von_mises_pa``, where the shell stage computed one: the largest peak with the
fin's loads moved up to a rope diameter along its edge, ``shell.strikes``) and σ_allow the
shell summary's ``allowable_pa`` for that fin, or — only when the key is absent — the fin
material's yield strength from ``resolved.json`` (``case.missile.material.yield_strength``);
the report says which source each fin used. When the peak carries an error estimate
(``peak_error_estimate_rel``) and ``|MS| ≤`` the estimate (σ ± its error straddles the
allowable) the verdict is marked "within the error estimate" and a warning is raised. The
overall verdict is PASS only when every fin passes beyond its error estimate: a pass within it is
UNDECIDED (the peak plus its estimated error reaches the allowable; the resolution does not decide
it), a fail within it stays FAIL (the conservative side).

A fin whose contact load alternated from one sample to the next for longer than the collide stage's
limit (collide summary ``fin_load_alternation_samples`` above ``fin_load_alternation_limit_samples``:
an explicit contact step past its stability limit, ``collide.metrics.load_alternation_runs``) has
no defined peak: its stresses are step noise, neither safe nor conservative. Such a fin decides
nothing: the banner is FAIL only on the other fins' failures, and otherwise UNDECIDED, naming it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from flexnet_fe.report.rundir import RunData, fin_results, yield_strength
from flexnet_fe.runs import FIN_STRIKE_ENVELOPE, governing_peak

ENERGY_TOL_REL = 0.05
"""Energy-balance error above which a warning is raised when the stage gives no tolerance of
its own (``energy_tolerance_rel``). 5 %: the usual acceptance of an explicit run's energy
ratio (glstat total / initial + external work within a few per cent)."""

PEAK_ERROR_TOL_REL = 0.10
"""Peak-stress error estimate above which the peak is flagged as unconverged (10 %)."""

WARNING_KEYS = ("warnings",)
"""Summary keys holding lists of one-line warnings (brief: any stage, any section level)."""

TUNNELLING_KEYS = ("tunnelling", "tunnelled")
"""Boolean summary keys that flag ropes passing through the missile unresisted."""


@dataclass(frozen=True)
class Warning_:
    """One line of the red box: the stage (or 'run') and the text."""

    stage: str
    text: str


@dataclass(frozen=True)
class FinVerdict:
    """One fin's line of the verdict (SI values; ``None`` where the summary has no value).

    margin      MS = allowable / von Mises − 1 [–]
    passed      MS ≥ 0 (None when no allowable or no stress)
    marginal    |MS| within the peak's relative error estimate
    loads_alternate  the fin's load alternated past the collide stage's limit (no defined peak)
    """

    name: str
    von_mises_pa: float | None
    max_principal_pa: float | None
    time_s: float | None
    location_m: list | None
    error_rel: float | None
    allowable_pa: float | None
    allowable_source: str
    margin: float | None
    passed: bool | None
    marginal: bool
    loads_alternate: bool = False
    error_kind: str | None = None
    """how the error estimate was made: 'zz' (the stress recovery's), 'mesh_halving' (shell.peak_check)"""
    check_pa: float | None = None
    """the peak on the mesh halved at the loads (shell.peak_check) [Pa]"""
    run_pa: float | None = None
    """the run's own peak [Pa] where ``von_mises_pa`` is its strike envelope (shell.strike_envelope),
    else None"""


@dataclass(frozen=True)
class Item:
    """A labelled line of the missile / flight part of the verdict: label, value text, note."""

    label: str
    value: str
    note: str = ""
    bad: bool = False


@dataclass(frozen=True)
class Verdict:
    """What the top of the report shows."""

    overall: str                      # PASS | FAIL | UNDECIDED | INCOMPLETE
    overall_reason: str
    fins: tuple[FinVerdict, ...]
    missile: tuple[Item, ...]
    flight: tuple[Item, ...]
    warnings: tuple[Warning_, ...] = field(default_factory=tuple)


def margin_of_safety(allowable_pa: float, stress_pa: float) -> float:
    """MS = allowable / stress − 1 [–]; +inf for a zero stress."""
    return math.inf if stress_pa <= 0.0 else allowable_pa / stress_pa - 1.0


def _num(v) -> float | None:
    return float(v) if isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) else None


def fin_verdict(name: str, res: dict, yield_pa: float | None, yield_what: str,
                alternating: frozenset[str] = frozenset()) -> FinVerdict:
    """A fin's verdict from its shell-summary entry (``allowable_pa`` first, else yield);
    ``alternating``: the fins whose loads alternated (:func:`alternating_fins`)."""
    vm, allow = _num(governing_peak(res)), _num(res.get("allowable_pa"))
    if allow is not None:
        source = "shell summary allowable_pa"
    elif yield_pa is not None:
        allow, source = yield_pa, f"yield strength of {yield_what} (resolved.json case.missile.material)"
    else:
        source = f"none: {yield_what}"
    err = _num(res.get("peak_error_estimate_rel"))
    ms = margin_of_safety(allow, vm) if allow is not None and vm is not None else None
    return FinVerdict(
        name=name, von_mises_pa=vm, max_principal_pa=_num(res.get("peak_max_principal_pa")),
        time_s=_num(res.get("peak_time_s")), location_m=res.get("peak_location_m"),
        error_rel=err, allowable_pa=allow, allowable_source=source, margin=ms,
        passed=None if ms is None else ms >= 0.0,
        marginal=ms is not None and err is not None and math.isfinite(ms) and abs(ms) <= err,
        loads_alternate=name in alternating, error_kind=res.get("peak_error_estimate_kind"),
        check_pa=_num((res.get("peak_check") or {}).get("peak_von_mises_pa")),
        run_pa=_num(res.get("peak_von_mises_pa")) if FIN_STRIKE_ENVELOPE in res else None)


def alternating_fins(run: RunData) -> frozenset[str]:
    """Fins whose contact load alternated from one sample to the next for more samples than the
    collide stage's limit (collide summary ``fin_load_alternation_samples``,
    ``fin_load_alternation_limit_samples``); empty when the collide section lacks either."""
    stage = next((s for s in run.stages if s.name == "collide"), None)
    section = stage.section if stage is not None and stage.complete else None
    runs = (section or {}).get("fin_load_alternation_samples")
    limit = _num((section or {}).get("fin_load_alternation_limit_samples"))
    if not isinstance(runs, dict) or limit is None:
        return frozenset()
    return frozenset(n for n, r in runs.items() if _num(r) is not None and r > limit)


def _unprefixed(text: str, stage: str) -> str:
    """A stage's warning without its own leading "<stage>: " (the report shows the stage beside it)."""
    return text[len(stage) + 2:] if text.startswith(f"{stage}: ") else text


def _walk_warnings(stage: str, node: Any, path: str, out: list[Warning_]) -> None:
    """Collect ``warnings`` lists, tunnelling flags, energy errors over tolerance and
    ``converged: false`` flags at any depth of a summary section."""
    if not isinstance(node, dict):
        return
    where = f" ({path})" if path else ""
    tol = _num(node.get("energy_tolerance_rel")) or ENERGY_TOL_REL
    for key, v in node.items():
        if key in WARNING_KEYS and isinstance(v, list):
            out.extend(Warning_(stage, f"{_unprefixed(str(w), stage)}{where}") for w in v)
        elif key in TUNNELLING_KEYS and v is True:
            n = node.get("segment_crossings_unresolved")
            extra = f": {n} rope-segment crossings not resolved" if isinstance(n, int) else ""
            out.append(Warning_(stage, f"tunnelling{where}: ropes passed through the missile "
                                       f"surface unresisted{extra}"))
        elif key == "energy_error_rel" and _num(v) is not None and abs(v) > tol:
            out.append(Warning_(stage, f"energy balance error {abs(v):.3g} exceeds the tolerance "
                                       f"{tol:.3g}{where}"))
        elif key == "converged" and v is False:
            out.append(Warning_(stage, f"not converged{where}"))
        elif isinstance(v, dict):
            _walk_warnings(stage, v, f"{path}.{key}" if path else key, out)


def collect_warnings(run: RunData, fins: tuple[FinVerdict, ...]) -> list[Warning_]:
    """Every warning of the run, in stage order: status failures, stages not finished, the
    summary's own warnings and flags, unconverged peaks, loaded fins without a shell result."""
    out: list[Warning_] = []
    for s in run.stages:
        if s.state == "failed":
            out.append(Warning_(s.name, f"stage FAILED: {s.error or '(no error recorded)'}"))
        elif s.state == "running":
            out.append(Warning_(s.name, "stage still 'running' in status.json: running now, or "
                                        "interrupted (killed) — its files may be partial"))
        elif s.state == "interrupted":
            out.append(Warning_(s.name, f"stage INTERRUPTED: {s.error or 'outputs up to the interrupt kept'}"))
        elif s.state == "stale":
            out.append(Warning_(s.name, "stage STALE: an upstream stage changed or failed since it ran; no result"))
        elif s.state in ("pending", "unknown") and s.requested:
            out.append(Warning_(s.name, f"requested by the case but '{s.state}': no result"))
        elif s.state == "done" and s.section is None:
            out.append(Warning_(s.name, "done in status.json but summary.json has no section"))
        if s.complete:
            _walk_warnings(s.name, s.section, "", out)
    for note in run.notes:
        if "case hash" in note:
            out.append(Warning_("run", note + " (stale results)"))
    stage_said = " ".join(w.text for w in out if w.stage == "shell")
    for f in fins:
        # the shell stage names each peak over its own tolerance: do not say it twice
        said = f"shell {f.name}: peak von Mises" in stage_said and "estimated error" in stage_said
        if f.error_rel is not None and f.error_rel > PEAK_ERROR_TOL_REL and not said:
            out.append(Warning_("shell", f"fin {f.name}: peak stress error estimate {f.error_rel:.3g} "
                                         f"> {PEAK_ERROR_TOL_REL:.3g} (unconverged peak)"))
        if f.marginal:
            out.append(Warning_("shell", f"fin {f.name}: margin of safety {f.margin:+.3g} lies within "
                                         f"the peak's error estimate ±{f.error_rel:.3g}: PASS/FAIL is "
                                         "not decided by this resolution"))
    out.extend(_unsolved_loaded_fins(run))
    return out


def _unsolved_loaded_fins(run: RunData) -> list[Warning_]:
    """Fins the collide stage loaded (impulse > 0) that have no shell result."""
    summ = run.summary or {}
    impulses = (summ.get("collide") or {}).get("fin_impulse_ns")
    shell = next((s for s in run.stages if s.name == "shell"), None)
    if not isinstance(impulses, dict) or shell is None or not shell.complete:
        return []
    solved = set(fin_results(shell.section))
    return [Warning_("shell", f"fin {n} received {v:.3g} N·s of contact impulse but has no shell result")
            for n, v in impulses.items() if _num(v) and v > 0 and n not in solved]


def _missile_items(run: RunData) -> list[Item]:
    """Δv, (filtered) peak acceleration, impulse, contact duration, pass-through / capture."""
    from flexnet_fe.report.units import unit_of, with_unit

    stage = next((s for s in run.stages if s.name == "collide"), None)
    if stage is None or not stage.complete:
        return [Item("collision", "no result", f"collide stage {stage.state if stage else 'absent'}", True)]
    c = stage.section
    items = []
    if _num(c.get("delta_v_mps")) is not None:
        items.append(Item("Δv of the missile", with_unit(c["delta_v_mps"], unit_of("delta_v_mps")),
                          "collide summary delta_v_mps"))
    elif _num(c.get("dv_over_v")) is not None:
        v0 = _num(((run.case.get("collide") or {}).get("impact_speed")))
        if v0 is not None:
            items.append(Item("Δv of the missile", with_unit(c["dv_over_v"] * v0, unit_of("_mps")),
                              f"= dv_over_v {c['dv_over_v']:.4g} × impact speed {v0:.4g} m/s (resolved.json)"))
        else:
            items.append(Item("|Δv| / v", f"{c['dv_over_v']:.4g}", "impact speed not in resolved.json"))
    if _num(c.get("peak_accel_mps2")) is not None:
        cfc = c.get("cfc")
        note = (f"SAE J211 CFC {cfc} filtered" if cfc is not None else
                "NOT CFC-filtered: mean over each output interval of collide/history.csv")
        t = _num(c.get("peak_accel_time_s"))
        when = f" at {t * 1e3:.4g} ms" if t is not None else ""
        items.append(Item("peak CG acceleration", with_unit(c["peak_accel_mps2"], unit_of("_mps2")) + when, note))
    for key, label in (("impulse_ns", "impulse on the missile"), ("contact_duration_s", "contact duration")):
        if _num(c.get(key)) is not None:
            items.append(Item(label, with_unit(c[key], unit_of(key)), f"collide summary {key}"))
    if isinstance(c.get("passed_through"), bool):
        items.append(_outcome_item(c))
    if isinstance(c.get("fin_coupling"), dict):
        items.append(_coupling_item(c["fin_coupling"]))
    return items


def _coupling_item(fc: dict) -> Item:
    """The staggered fin coupling's row: how far the fins' motion moved the fin impulses from rigid
    fins — the fin whose impulse changed most in N s (not in per cent: a graze's 0.03 N s may move
    by tens of per cent) and its own move — from the collide summary."""
    moves = {f: m for f, m in (fc.get("fin_impulse_move_rel") or {}).items() if _num(m) is not None}
    rigid = (fc.get("rigid") or {}).get("fin_impulse_ns") or {}
    worst = max(moves, key=lambda f: abs(moves[f] * (_num(rigid.get(f)) or 0.0)), default=None)
    text = "staggered (the impact again with the fins moving as the shell computes them)"
    if worst is not None:
        text += f"; against rigid fins: {worst}'s impulse {100 * moves[worst]:+.2f} %"
    note = "collide summary fin_coupling"
    if _num(fc.get("fin_impulse_largest_move_rel")) is not None:
        note += f"; largest impulse change over the largest fin impulse {100 * fc['fin_impulse_largest_move_rel']:.2f} %"
    if _num(fc.get("dv_over_v_move_rel")) is not None:
        note += f"; Δv/v {100 * fc['dv_over_v_move_rel']:+.3f} %"
    return Item("fin coupling", text, note)


def _outcome_item(c: dict) -> Item:
    """Pass-through or capture, from the collide summary; a run stopped by its time cap while the
    rope still pressed on the missile has no outcome yet (``stop_reason``, ``force_at_end_n``): it
    is shown as such and flagged, not called a capture."""
    if c["passed_through"]:
        return Item("net", "passed through", "collide summary passed_through")
    force = _num(c.get("force_at_end_n"))
    if c.get("stop_reason") in ("duration", "max_duration") and force is not None and force > 0:
        t_end = _num(c.get("end_time_s"))
        when = f" at {t_end * 1e3:.4g} ms" if t_end is not None else ""
        return Item("net", f"still on the missile when the run stopped{when}: outcome not determined",
                    f"collide summary stop_reason {c['stop_reason']}, force at the end {force:.4g} N "
                    "(raise collide.max_duration)", True)
    return Item("net", "captured / carried forward", "collide summary passed_through")


def _flight_items(run: RunData) -> list[Item]:
    """Hit or miss, miss distance against the lethal radius, and the damage the flight used."""
    stage = next((s for s in run.stages if s.name == "flight"), None)
    if stage is None or (stage.requested is False and not stage.complete):
        return []  # (a stage the case does not run: status.json lists every stage, pending)
    if not stage.complete:
        return [Item("flight outcome", "no result", f"flight stage {stage.state}", True)]
    f = stage.section
    items = []
    miss, lethal = _num(f.get("miss_distance_m")), _num(f.get("lethal_radius_m"))
    if isinstance(f.get("hit"), bool):
        text = "HIT" if f["hit"] else "MISS"
        detail = (f"miss distance {miss:.4g} m {'≤' if f['hit'] else '>'} lethal radius {lethal:.4g} m"
                  if miss is not None and lethal is not None else "")
        items.append(Item("missile against the aircraft", text, detail, bad=f["hit"]))
    dmg = f.get("damage_from_shell")
    wing = _num(f.get("wing_damage"))
    if isinstance(dmg, dict):
        # flight.damage.damage_from_shell: the area fraction each fin loses by the damage law
        frac = dmg.get("lost_area_fraction") or {}
        parts = ", ".join(f"{k} {100 * v:.3g} %" for k, v in frac.items() if _num(v))
        law, eps = dmg.get("law"), _num(dmg.get("failure_strain"))
        note = f"damage law {law}" + (f", failure strain {eps:g}" if eps is not None else "") + \
            (f", allowable from the {dmg['allowable_from']}" if dmg.get("allowable_from") else "")
        items.append(Item("fin area lost, used by the flight (from the shell stage)", parts or "none", note))
    elif wing is not None:
        items.append(Item("damage used by the flight", f"wing damage {100 * wing:.3g} %", "from the case file"))
    return items


def build_verdict(run: RunData) -> Verdict:
    """The verdict of a run directory (see the module doc)."""
    yield_pa, yield_what = yield_strength(run.case)
    shell = next((s for s in run.stages if s.name == "shell"), None)
    alternating = alternating_fins(run)
    fins = tuple(fin_verdict(n, r, yield_pa, yield_what, alternating)
                 for n, r in (fin_results(shell.section).items() if shell and shell.complete else []))
    warnings = collect_warnings(run, fins)
    failed = [f.name for f in fins if f.passed is False and not f.loads_alternate]
    undecided = [f.name for f in fins if f.passed is None]
    noisy = [f.name for f in fins if f.loads_alternate]
    if failed:
        overall, reason = "FAIL", "margin of safety < 0 on " + ", ".join(failed)
    elif shell is None or not shell.complete:
        overall, reason = "INCOMPLETE", f"no fin stresses (shell stage {shell.state if shell else 'absent'})"
    elif undecided or not fins:
        overall, reason = "INCOMPLETE", ("no allowable for " + ", ".join(undecided)) if undecided else "no fin loaded"
    elif noisy:
        overall, reason = "UNDECIDED", ("the contact loads on " + ", ".join(noisy) + " alternate from one sample to "
                                        "the next (an explicit contact step past its stability limit): their peaks "
                                        "are not defined (see the collide warnings)")
    elif any(f.marginal for f in fins):
        close = ", ".join(f.name for f in fins if f.marginal)
        overall, reason = "UNDECIDED", (f"margin of safety ≥ 0 on every solved fin, but within the peak's error "
                                        f"estimate on {close}: not decided at this resolution (see the warnings)")
    else:
        overall, reason = "PASS", "margin of safety ≥ 0 on every solved fin"
    if overall == "FAIL" and any(f.marginal for f in fins):
        reason += " (some margins lie within the error estimate: see the warnings)"
    if overall == "FAIL" and noisy:
        reason += f" (the peaks of {', '.join(noisy)} are not defined: their loads alternate)"
    interval = _num(shell.section.get("load_sample_interval_s")) if shell and shell.complete else None
    if overall != "INCOMPLETE" and interval is not None:
        # shell.stage.load_sampling_warning: coarse, the peaks are under-estimated; fine, they
        # still follow the rope's discretisation
        if shell.section.get("load_sampling_resolved"):
            reason += (f", at the fin loads' {interval * 1e6:.3g} µs sampling; the peaks are not converged in "
                       "the rope's discretisation and follow its transverse stiffness (see the warnings)")
        else:
            reason += (f", at the fin loads' {interval * 1e6:.3g} µs sampling, which under-estimates the peaks "
                       "(see the warnings)")
    return Verdict(overall=overall, overall_reason=reason, fins=fins, missile=tuple(_missile_items(run)),
                   flight=tuple(_flight_items(run)), warnings=tuple(warnings))

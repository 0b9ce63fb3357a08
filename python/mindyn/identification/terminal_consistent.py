"""The lines of the consistent estimate in the terminal text of an identification
(``mindyn identify --consistent``, :func:`consistent_lines`): its headline, how its prior's
weight was chosen, its pseudo-inertias, and its errors beside the ordinary estimate's."""

from __future__ import annotations

from .terminal import (
    _pct,
    _rms_lines,
)


def _headline(cfit, cval, fit, val) -> str:
    """The first figures of ``identify --consistent``: the consistent estimate's own errors."""
    return (
        "  Headline, the physically consistent estimate: overall relative error "
        f"{_pct(cfit['overall_relative']).strip()} on the identification data"
        + (f", {_pct(cval['overall_relative']).strip()} on the validation data" if cval else "")
        + f" (unconstrained least-squares estimate: {_pct(fit['overall_relative']).strip()}"
        + (f", {_pct(val['overall_relative']).strip()}" if val else "")
        + "); each table below names its estimate"
    )


def _weight_lines(ce: dict) -> list[str]:
    """How the prior's weight was chosen, and per link whether the data or the prior hold it
    (``ce``: the consistent estimate's ``consistent_estimate`` JSON fields)."""
    ch = ce["prior_weight_choice"]
    lines = []
    if ch is not None:
        lines.append(
            f"  prior weight {ch['chosen']:g} chosen by the {ch['rule']}; log marginal "
            f"likelihood at each candidate weight ({ch['log_evidence_unit']}):"
        )
        lines.append(
            "    "
            + "  ".join(
                f"{w:g}: {e:.1f}" + (" (chosen)" if w == ch["chosen"] else "")
                for w, e in zip(ch["candidates"], ch["log_evidence"])
            )
        )
        if ch["newton_not_converged"]:
            lines.append(
                f"    {ch['newton_not_converged']} of the candidates' Newton descents stopped "
                "before converging (their likelihoods are approximate)"
            )
        if ch["at_grid_end"]:
            lines.append(
                "    the chosen weight is at the end of the candidates: the optimum may lie "
                "beyond (give prior_weight= to go further)"
            )
    elif ce["prior_weight"]:
        lines.append(f"  prior weight {ce['prior_weight']:g} (given)")
    if ce["links"]:
        from .prior import MASS_EVIDENCE

        lines.append(
            "  per link: mass [kg] (posterior standard deviation), description's mass [kg], fit "
            "worse with the mass held at the description's [noise variances], the mass "
            "determined by (with the data's standard deviation); identifiable directions of "
            "the link's parameters determined by the data, the link's parameters determined by:"
        )
        for lk in ce["links"]:
            sd = lk["mass_data_std"]
            lines.append(
                f"  {lk['link']:<24} {lk['mass']:10.4g} ({lk['mass_std']:.3g}) "
                f"{lk['description_mass']:10.4g} {lk['mass_fit_increase']:10.4g} "
                f"{lk['mass_verdict']:<10}"
                + (f" ({sd:.3g})" if lk["mass_verdict"] in ("data", "data+prior") else " " * 8)
                + f" {lk['directions_by_data']:3d} of {lk['identifiable_directions']:<3d} "
                f"{lk['verdict']}"
                + ("" if lk["mass_profile_converged"] else " (mass profile not converged)")
            )
        lines.append(
            f"  (mass by data: held at the description's, the fit is worse by at least "
            f"{MASS_EVIDENCE:g} noise variances, the data's standard deviation |m - m0| / "
            "sqrt(worse); data+prior: the fit not, but the whole objective worse by as much "
            "(the prior ties the mass to the link's moments, which the data fix), standard "
            "deviation from that; else by the priors (the description's mass within two "
            "standard deviations); unknown: that fit did not converge; identifiable: "
            "the combinations of the link's own parameters that the torques determine, by the "
            "data when the priors' share of their variance, -d ln(variance) / d ln(weight), is "
            "below 0.5; data: their mean share "
            "below 0.5; partly: above, but some of them below; prior: none)"
        )
        better = [lk for lk in ce["links"] if lk["mass_fit_increase"] < 0]
        if better:  # not a defect: that fit is not the minimiser of the fit alone
            lines.append(
                "  (a negative fit increase, "
                + ", ".join(
                    f"{lk['link']} {lk['mass_fit_increase']:.3g} (whole objective "
                    f"{lk['mass_objective_increase']:+.3g})"
                    for lk in better
                )
                + ": with the mass held the estimate minimises the whole objective, fit plus "
                "priors, not the fit alone, so its fit can be slightly better than the "
                "estimate's while the whole objective is not)"
            )
    return lines


def _cost_lines(cost: dict | None) -> list[str]:
    """Where consistency costs the fit (``cost``: ``consistent_estimate.constraint_cost`` of
    the JSON; nothing for older JSONs)."""
    if not cost:
        return []
    total = cost["total"]
    if total is None:
        return ["  cost of consistency: not measured (its solve failed; see the notes)"]
    head = (
        f"  cost of consistency: the best consistent estimate (no prior) fits {total:.4g} noise "
        "variances worse than the unconstrained fit"
    )
    if cost["links"] is None:
        return [head + " (negligible: the data ask for nothing non-physical)"]
    parts = [
        f"{nm} {v:.4g}" if v is not None else f"{nm} not solved" for nm, v in cost["links"].items()
    ]
    if cost["joint_terms"] is not None:
        parts.append(
            f"joint terms (Ia, Fv, Fc >= 0, friction dissipative) {cost['joint_terms']:.4g}"
        )
    lines = [head + "; of it, lifting one constraint alone recovers:", "    " + "  ".join(parts)]
    shares = {**cost["links"], "joint terms": cost["joint_terms"]}
    if cost["major"]:
        lines.append(
            "  most at "
            + " and ".join(f"{nm} ({100 * shares[nm] / total:.0f} %)" for nm in cost["major"])
            + ": the torques ask there for values no rigid body (or no positive friction or rotor "
            "inertia) has: the description's geometry of those links, or effects the model "
            "lacks (friction, elasticity, torque-sensor gains), disagree with the log"
        )
    else:
        lines.append("  spread over the links: no one constraint accounts for half of it")
    return lines


def _noise_lines(noise: dict) -> list[str]:
    """What one noise variance of the fit term is (``noise``: ``noise_variance_factor`` of the
    JSON)."""
    if not noise:
        return []
    measured = noise["residuals"]
    head = f"  one noise variance: the residual variance x {noise['factor']:.3g}, "
    if measured is None:  # the rule says why: "not measured (...)"
        return [
            head + f"the data path's factor ({noise['data_path']:.3g}); the "
            f"residuals' own factor: {noise['residuals_rule']}"
        ]
    return [
        head + f"the larger of the data path's factor ({noise['data_path']:.3g}) and the "
        f"residuals' own ({measured:.3g}: {noise['residuals_rule']})"
    ]


def _tie_break_text(tie: dict | None) -> str:
    """What of the fit increase the no-prior tie-break took (``tie``: the JSON's
    ``consistent_estimate.tie_break``; nothing when it was not taken)."""
    if not tie:
        return ""
    return (
        f" (the optimum's {tie['optimum_fit_increase']:.4g} plus at most {tie['slack']:g} noise "
        "variance of designed slack: with no prior, the estimate is the one nearest the "
        "description among those within that slack of the optimum's fit)"
    )


def _consistent_lines(doc, fit, val, cfit, cval, low) -> list[str]:
    """The lines of ``mindyn identify --consistent``: pseudo-inertias, errors side by side
    (``doc``: the consistent estimate's JSON fields, ``low``: its mass matrix's smallest
    eigenvalue over the data)."""
    ce = doc["consistent_estimate"]
    un = ce["unconstrained_violating_links"]
    weight = ce["prior_weight"]
    lines = [
        f"Physically consistent estimate ({ce['solver']}, {ce['status']}, {ce['seconds']:.3g} s"
        + (f", prior weight {weight:g}" if weight else ", no prior")
        + f"): total mass {doc['total_mass']:.4g} kg; fit "
        f"{ce['fit_increase_noise_variances']:.4g} noise variances worse than the unconstrained "
        "fit with all base parameters" + _tie_break_text(ce.get("tie_break")),
        *_noise_lines(ce.get("noise_variance_factor") or {}),
        *_cost_lines(ce.get("constraint_cost")),
        *_weight_lines(ce),
        "  smallest pseudo-inertia eigenvalue per link [kg] (unconstrained: its realisation "
        "nearest the description):",
        f"  {'link':<24} {'unconstrained':>14} {'consistent':>14}",
    ]
    before = ce["unconstrained_pseudo_inertia_min_eig"]
    for nm, b in doc["pseudo_inertia_min_eig"].items():
        lines.append(
            f"  {nm:<24} {before[nm]:14.4g} {b:14.4g}" + ("  violated" if nm in un else "")
        )
    lines.append(
        "  unconstrained estimate violates physical consistency at: " + ", ".join(un)
        if un
        else "  unconstrained estimate: a consistent realisation nearest the description"
    )
    lines.append(f"  {'overall relative error':<24} {'unconstrained':>14} {'consistent':>14}")
    lines.append(
        f"  {'identification data':<24} {_pct(fit['overall_relative']):>14} "
        f"{_pct(cfit['overall_relative']):>14}"
    )
    if cval is not None:
        lines.append(
            f"  {'validation data':<24} {_pct(val['overall_relative']):>14} "
            f"{_pct(cval['overall_relative']):>14}"
        )
    for what, un_m, co_m in (("identification", fit, cfit), ("validation", val, cval)):
        for kind in ("raw", "moving"):
            if co_m is not None and co_m.get(kind) is not None:
                lines.append(
                    f"  {what + ', ' + kind:<24} {_pct(un_m[kind]['overall_relative']):>14} "
                    f"{_pct(co_m[kind]['overall_relative']):>14}"
                )
    lines.append(
        f"  mass matrix of the consistent model: smallest eigenvalue over the data {low:.4g} "
        + ("(positive definite at every sample)" if low > 0 else "(NOT positive definite)")
    )
    for note in ce["notes"]:
        lines.append(f"  note: {note}")
    return lines


def consistent_lines(report) -> tuple[str, list[str]]:
    """The headline of the consistent estimate of ``report`` (its errors beside the ordinary
    estimate's) and its section of the text, after the ordinary estimate's errors."""
    fit, val = report.fit, report.validation
    cfit, cval = report.consistent_fit, report.consistent_validation
    vfiles = report.logs.validation.files
    out = _consistent_lines(report.consistent_doc, fit, val, cfit, cval, report.mass_matrix_min_eig)
    out.append(_rms_lines("identification data, consistent estimate", cfit))
    if cval is not None:
        out.append(_rms_lines(f"validation data ({', '.join(vfiles)}), consistent estimate", cval))
    return _headline(cfit, cval, fit, val), out

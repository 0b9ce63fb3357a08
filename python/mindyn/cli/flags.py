"""Library messages as the command line says them: the library's keywords (``offset=True``,
``prior_weight=``) as the command's flags (``--offset``, ``--prior-weight``)."""

from __future__ import annotations

import re

#: Library keywords that library messages name (``friction=True``, ``tip='link'``,
#: ``prior_weight=``) whose command-line flag is the keyword with dashes (``--prior-weight``),
#: those of identification and of the generated code (``what``, ``trig``, ``name``) alike.
LIBRARY_OPTIONS = (
    "columns",
    "consistent",
    "contacts",
    "currents",
    "cutoff",
    "decimate",
    "drive_gain",
    "drive_side",
    "edge",
    "energy_window",
    "filter",
    "friction",
    "friction_model",
    "friction_width",
    "integral_window",
    "integration",
    "joint_terms",
    "lang",
    "method",
    "min_velocity",
    "minimise",
    "model",
    "name",
    "numeric",
    "offset",
    "order",
    "period",
    "periods",
    "position_noise",
    "prior_weight",
    "quantization",
    "root_joint",
    "rotor",
    "rsd_threshold",
    "snap",
    "tau_max",
    "tip",
    "topic",
    "torque",
    "torque_limit",
    "torque_noise",
    "torque_unit",
    "trig",
    "validate",
    "validate_currents",
    "velocity_noise",
    "what",
    "wrench_frame",
)
# the keywords whose flag is not their name with dashes: (keyword, value) -> flag, None for any
# value (the value then follows the flag)
_FLAG_OF = {
    ("period", None): "--excitation-period",
    ("decimate", "False"): "--no-decimate",
    ("contacts", None): "--contact",
    ("tau_max", None): "--torque-limit",
}
_NUMBER = r"-?\d+(?:\.\d*)?(?:[eE][-+]?\d+)?"
_LIBRARY_OPTION = re.compile(
    r"\b(" + "|".join(LIBRARY_OPTIONS) + r")="
    r"(?:(True|False)\b|'([^']*)'(?: or '([^']*)')?|(" + _NUMBER + r")(?![\w.])|(?![\w'\"]))"
)


def _flag(key: str) -> str:
    """The flag of library keyword ``key`` whatever its value (``contacts`` -> ``--contact``)."""
    return _FLAG_OF.get((key, None), "--" + key.replace("_", "-"))


def library_options_as_flags(text: str) -> str:
    """A library message as the command line says it: the keywords of :data:`LIBRARY_OPTIONS`
    as their flags (``offset=True`` -> ``--offset``, ``decimate=False`` -> ``--no-decimate``,
    ``method='recursive'`` -> ``--method recursive``, ``friction_model='smooth' or 'auto'`` ->
    ``--friction-model smooth or auto``, ``min_velocity=0`` -> ``--min-velocity 0``,
    ``prior_weight=`` -> ``--prior-weight``, ``period=`` -> ``--excitation-period``)."""

    def flag(m: re.Match) -> str:
        key, truth, word, other, number = m.groups()
        special = _FLAG_OF.get((key, truth))
        if special is not None:
            return special
        if truth == "False":  # no flag says it
            return m.group(0)
        name = _flag(key)
        if word is not None:
            return f"{name} {word}" + ("" if other is None else f" or {other}")
        return name if number is None else f"{name} {number}"

    return _LIBRARY_OPTION.sub(flag, text)


def argument_as_flag(text: str) -> str:
    """An argument error of the library (``contacts names 'x', ...``: it starts with the
    argument's name) as the command line says it, when that argument is one of
    :data:`LIBRARY_OPTIONS` (``--contact names 'x', ...``)."""
    key, sep, rest = text.partition(" ")
    if not sep or key not in LIBRARY_OPTIONS:
        return text
    return _flag(key) + sep + rest

"""Bad-input campaign over the CLI, the loaders and the Python API.

Each case runs in a forked child (after the imports) with a wall-clock limit and an address-space
limit; the parent classifies the outcome:
  ok        exit 0
  error     non-zero exit with exactly one stderr line starting "mindyn: error:" (CLI), or a
            mindyn.Error / ValueError / FileNotFoundError subclass raised by the API
  internal  the CLI's last-resort handler (exit 70) or another exception type from the API
  trace     a traceback on stderr
  crash     killed by a signal
  hang      over the time limit
usage: .venv/bin/python fuzz/campaign.py OUTDIR [N_PER_KIND] [SEED]

N_PER_KIND cases of each kind (random command lines built from the parser's own options, mutated
URDF, YAML and CSV files through the command line, Python API calls with bad arrays); the counts
per kind and outcome are printed, and every case that is not ok or error is written with its
input to OUTDIR/bad.json.
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import random
import re
import resource
import signal
import sys
import time
import traceback
from pathlib import Path

import mindyn
import numpy as np
from mindyn import cli

OUT = Path(sys.argv[1])
N = int(sys.argv[2]) if len(sys.argv) > 2 else 200
rng = random.Random(int(sys.argv[3]) if len(sys.argv) > 3 else 0)
TIME = 60
MEM = 6 << 30
OUT.mkdir(parents=True, exist_ok=True)
URDF = Path(__file__).resolve().parents[1] / "examples" / "urdf" / "ur5.urdf"


def run_child(fn):
    """Run fn() in a fork; fn returns ('kind', detail)."""
    r, w = os.pipe()
    pid = os.fork()
    if pid == 0:
        os.close(r)
        resource.setrlimit(resource.RLIMIT_AS, (MEM, MEM))
        try:
            res = fn()
        except BaseException as e:  # noqa: BLE001
            res = ("trace", f"{type(e).__name__}: {e}"[:300])
        os.write(w, json.dumps(res).encode()[:60000])
        os._exit(0)
    os.close(w)
    t0 = time.time()
    while True:
        done, status = os.waitpid(pid, os.WNOHANG)
        if done:
            break
        if time.time() - t0 > TIME:
            os.kill(pid, signal.SIGKILL)
            os.waitpid(pid, 0)
            os.close(r)
            return ("hang", f">{TIME}s")
        time.sleep(0.01)
    data = b""
    while chunk := os.read(r, 65536):
        data += chunk
    os.close(r)
    if os.WIFSIGNALED(status):
        return ("crash", f"signal {os.WTERMSIG(status)}")
    try:
        return tuple(json.loads(data))
    except ValueError:
        return ("crash", "no result")


def cli_case(argv):
    def fn():
        err, out = io.StringIO(), io.StringIO()
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(out):
            try:
                code = cli.main(argv)
            except SystemExit as e:
                code = e.code if isinstance(e.code, int) else 2
            except BaseException:  # noqa: BLE001
                return ("trace", traceback.format_exc()[-400:])
        e = err.getvalue()
        if "Traceback" in e:
            return ("trace", e[-400:])
        lines = [x for x in e.splitlines() if x.strip() and not x.startswith("usage:")]
        lines = [x for x in lines if not x.startswith(" ")]
        if code == 0:
            return ("ok", "")
        if code == 70:
            return ("internal", e.strip()[:300])
        errs = [x for x in lines if x.startswith("mindyn")]
        if errs and ("error" in errs[-1]):
            return ("error", errs[-1][:300])
        return ("trace", f"exit {code}: {e.strip()[:300]}")

    return fn


NUM_BAD = [
    "0",
    "-1",
    "-0",
    "1e308",
    "-1e308",
    "inf",
    "-inf",
    "nan",
    "1e-300",
    "1e9",
    "1_000",
    "",
    "abc",
    "0x10",
    "99999999999999999999999",
    "-99999999999999999999",
    "1.5",
    "3",
]
ROBOTS = ["planar2", "puma560", "zcr07s", "stanford"]


def parser_options():
    p = cli.build_parser()
    sub = [a for a in p._actions if a.__class__.__name__ == "_SubParsersAction"][0]
    out = {}
    for name, sp in sub.choices.items():
        opts = [a for a in sp._actions if a.option_strings and a.option_strings[0] != "-h"]
        out[name] = opts
    return out


def random_cli_argv(opts_by_cmd, files):
    cmd = rng.choice([c for c in opts_by_cmd if c != "demo"])
    argv = [
        cmd,
        rng.choice(
            ROBOTS
            + [files["urdf"], files["yaml"], "planar17", "planar9999", "puma999", "", files["dir"]]
        ),
    ]
    if cmd == "identify":
        argv.append(rng.choice([files["csv"], files["csv"], files["badcsv"], files["dir"], ""]))
    for a in rng.sample(opts_by_cmd[cmd], k=min(len(opts_by_cmd[cmd]), rng.randint(1, 4))):
        flag = a.option_strings[-1]
        if a.nargs == 0:
            argv.append(flag)
            continue
        k = (
            a.nargs
            if isinstance(a.nargs, int)
            else (1 if a.nargs in (None, "?") else rng.randint(1, 7))
        )
        if a.choices:
            vals = [rng.choice(list(a.choices) + ["bogus"]) for _ in range(k)]
        elif flag in ("--output", "-o", "--json", "--report", "--out"):
            vals = [
                rng.choice(
                    [
                        str(files["dir"]),
                        "",
                        "/proc/x/y",
                        "/nonexistent/a.csv",
                        str(files["tmp"] / f"o{rng.randint(0, 99)}.csv"),
                    ]
                )
            ]
        elif flag in ("--trajectory", "--validate", "--params", "--start"):
            vals = [
                rng.choice(
                    [files["csv"], files["badcsv"], files["yaml"], files["dir"], "", files["traj"]]
                )
            ]
        elif flag in ("--tip", "--order", "--gains", "--what", "--name", "--topic"):
            vals = [rng.choice(["", "x", "link6", "1,2,3", "a" * 1000, "-1"])]
        else:
            vals = [rng.choice(NUM_BAD) for _ in range(k)]
        argv += [flag, *vals]
    # Keep valid runs short.
    if cmd in ("excite",):
        argv += ["--maxiter", "3", "--starts", "1", "--quiet"]
    if cmd in ("track", "simulate") and "--duration" not in argv:
        argv += ["--duration", "0.2"]
    return argv


XML_MUT = [
    lambda s: s.replace('parent link="base_link"', 'parent link="wrist_3_link"', 1),
    lambda s: re.sub(r'<child link="([^"]+)"/>', r'\g<0><parent link="\1"/>', s, count=1),
    lambda s: re.sub(r'value="[^"]*"', 'value="1e308"', s, count=1),
    lambda s: re.sub(r'xyz="[^"]*"', 'xyz="1e308 0 0"', s, count=1),
    lambda s: re.sub(r'xyz="[^"]*"', 'xyz="nan 0 0"', s, count=1),
    lambda s: re.sub(r'ixx="[^"]*"', 'ixx="-1"', s, count=1),
    lambda s: re.sub(r'type="revolute"', 'type="floating"', s, count=1),
    lambda s: re.sub(r'type="revolute"', 'type="planar"', s, count=1),
    lambda s: re.sub(r'<axis xyz="[^"]*"', '<axis xyz="0 0 0"', s, count=1),
    lambda s: s[: rng.randint(0, len(s))],
    lambda s: s.replace("<joint", "<joint", 1) + s[s.find("<joint") : s.find("</joint>") + 8],
    lambda s: s.replace('name="shoulder_link"', 'name="base_link"', 1),
    lambda s: s.encode("utf-8").decode() + "\xff",
    lambda s: re.sub(r'lower="[^"]*"', 'lower="5" upper="-5"', s, count=1),
]


def mutate_text(s, kind):
    lines = s.splitlines()
    op = rng.randint(0, 9)
    if kind == "urdf" and op < 6:
        return rng.choice(XML_MUT)(s)
    i = rng.randrange(len(lines))
    if op < 2:
        del lines[i]
    elif op < 4:
        lines.insert(i, lines[rng.randrange(len(lines))])
    elif op < 7:
        number = r"-?\d+(\.\d+)?(e-?\d+)?"
        lines[i] = re.sub(number, lambda m: rng.choice(NUM_BAD), lines[i], count=1)
    elif op < 8:
        lines[i] = lines[i] + rng.choice([": [1, 2]", " !!python/object:os.system", "{", "]", "\t"])
    else:
        lines[i] = lines[i][: rng.randint(0, len(lines[i]))]
    return "\n".join(lines) + "\n"


def api_cases(n):
    robot = mindyn.load("planar2")
    bp = mindyn.base_parameters(robot)
    bad = [
        np.empty((0, 2)),
        np.empty((0,)),
        np.zeros(3),
        np.zeros((2, 3)),
        np.full(2, np.nan),
        np.full(2, np.inf),
        np.full(2, 1e308),
        None,
        "x",
        [1, 2, 3],
        [[1, 2]] * 2,
        np.zeros(2, dtype=complex),
        np.zeros((1, 1, 2)),
        np.zeros(2, dtype=object),
        3.0,
        np.zeros((5, 2)),
        np.zeros((0, 0)),
    ]
    fns = [
        ("inverse_dynamics", lambda a, b, c: robot.inverse_dynamics(a, b, c)),
        ("regressor", lambda a, b, c: robot.regressor(a, b, c)),
        ("mass_matrix", lambda a, b, c: robot.mass_matrix(a)),
        ("gravity", lambda a, b, c: robot.gravity_torque(a)),
        ("forward_dynamics", lambda a, b, c: robot.forward_dynamics(a, b, c)),
        ("fk", lambda a, b, c: robot.fk(a)),
        ("jacobian", lambda a, b, c: robot.jacobian(a)),
        ("base_regressor", lambda a, b, c: bp.regressor(a, b, c)),
        ("slotine_li", lambda a, b, c: mindyn.slotine_li_regressor(bp, a, b, b, c)),
        ("ik", lambda a, b, c: mindyn.ik(robot, a)),
        ("energy", lambda a, b, c: robot.energy(a, b)),
    ]
    good = np.zeros(2)
    for _ in range(n):
        name, f = rng.choice(fns)
        args = [good, good, good]
        for j in rng.sample(range(3), rng.randint(1, 3)):
            args[j] = rng.choice(bad)

        def fn(f=f, args=args):
            try:
                f(*args)
                return ("ok", "")
            except (mindyn.ModelError, ValueError, FileNotFoundError) as e:
                return ("error", str(e)[:200])
            except AttributeError as e:
                if "has no attribute" in str(e) and "robot" in repr(f):
                    return ("skip", str(e)[:200])
                return ("internal", f"{type(e).__name__}: {e}"[:300])
            except Exception as e:  # noqa: BLE001
                return ("internal", f"{type(e).__name__}: {e}"[:300])

        yield f"api {name} {[type(a).__name__ + str(getattr(a, 'shape', '')) for a in args]}", fn


def main():
    tmp = OUT / "files"
    tmp.mkdir(exist_ok=True)
    files = {
        "tmp": tmp,
        "dir": str(tmp),
        "urdf": str(URDF),
        "yaml": str(Path(mindyn.__file__).parent / "robots" / "puma560.yaml"),
    }
    # A small valid log and trajectory.
    traj = tmp / "traj.csv"
    with contextlib.redirect_stdout(io.StringIO()):
        cli.main(
            ["excite", "planar2", "--maxiter", "5", "--starts", "1", "--quiet", "-o", str(traj)]
        )
        cli.main(
            [
                "simulate",
                "planar2",
                "--trajectory",
                str(traj.with_suffix(".json")),
                "-o",
                str(tmp / "log.csv"),
            ]
        )
    files["csv"] = str(tmp / "log.csv")
    files["traj"] = str(traj.with_suffix(".json"))
    csv_text = Path(files["csv"]).read_text()
    files["badcsv"] = str(tmp / "bad.csv")
    Path(files["badcsv"]).write_text(mutate_text(csv_text, "csv"))
    cases = []
    opts = parser_options()
    for _ in range(N):
        argv = random_cli_argv(opts, files)
        cases.append((" ".join(repr(x) for x in argv), cli_case(argv)))
    urdf_text = URDF.read_text()
    yaml_text = Path(files["yaml"]).read_text()
    for i in range(N):
        f = tmp / f"m{i}.urdf"
        f.write_text(mutate_text(urdf_text, "urdf"), errors="surrogateescape")
        cases.append((f"urdf {f.name}", cli_case([rng.choice(["info", "base"]), str(f)])))
    for i in range(N):
        f = tmp / f"m{i}.yaml"
        f.write_text(mutate_text(yaml_text, "yaml"))
        cases.append((f"yaml {f.name}", cli_case([rng.choice(["info", "base"]), str(f)])))
    for i in range(N):
        f = tmp / f"m{i}.csv"
        t = mutate_text(csv_text, "csv")
        if rng.random() < 0.1:
            f.write_bytes(t.encode() + b"\xff\xfe")
        else:
            f.write_text(t)
        cases.append((f"csv {f.name}", cli_case(["identify", "planar2", str(f)])))
    cases += list(api_cases(N))
    counts, bad = {}, []
    t0 = time.time()
    for label, fn in cases:
        kind, detail = run_child(fn)
        counts.setdefault(label.split()[0] if not label.startswith("'") else "cli", {}).setdefault(
            kind, 0
        )
        counts[label.split()[0] if not label.startswith("'") else "cli"][kind] += 1
        if kind in ("trace", "internal", "crash", "hang"):
            bad.append((kind, label, detail))
    (OUT / "bad.json").write_text(json.dumps(bad, indent=1))
    print(json.dumps(counts, indent=1))
    print(f"{len(cases)} cases in {time.time() - t0:.0f} s; {len(bad)} bad (see {OUT}/bad.json)")


if __name__ == "__main__":
    main()

"""Regenerate every picture under ``docs/img`` with the commands the docs show.

Each picture is listed with the page that shows its commands and the commands themselves, exactly as
that page's code block has them (``tests/test_pictures_script.py`` checks that they are the same, so
the docs cannot drift from what made the pictures). The commands run from the repository's root,
``mcdm-pin`` as ``python -m mcdm_pin`` of this checkout; their scratch outputs go to ``out/``
(ignored by git), the pictures to ``docs/img``. A workspace store a command would write is removed
first (``mcdm-pin workspace`` refuses an existing store).

Usage::

    python tools/make_pictures.py                 # every picture (the benchmarks take minutes)
    python tools/make_pictures.py viewer_neck      # only these (names without .png)
    python tools/make_pictures.py --list           # the pictures and their commands
"""

from __future__ import annotations

import argparse
import os
import shlex
import shutil
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


@dataclass(frozen=True)
class Picture:
    """``docs/img/<name>.png``, made by ``commands`` as ``doc`` shows them (one string per command,
    continuation lines joined)."""

    name: str
    doc: str
    commands: tuple[str, ...]


TRAJ1 = (
    "mkdir -p out",
    "mcdm-pin solve robots/two_link_sr.yaml -t traj1 --case 1 -q --out out/traj1_case1.npz",
)

PICTURES = (
    Picture("traj1_case1_vs_case3_summary", "README.md", TRAJ1 + (
        "mcdm-pin solve robots/two_link_sr.yaml -t traj1 --case 3 -q --out out/traj1_case3.npz",
        "mcdm-pin plot out/traj1_case1.npz out/traj1_case3.npz --figures summary --format png "
        "--prefix traj1_case1_vs_case3_ --out docs/img",
    )),
    Picture("viewer_traj1_case1", "docs/pictures.md", TRAJ1 + (
        "mcdm-pin view robots/two_link_sr.yaml --results out/traj1_case1.npz --time 0.2 "
        "--html out/viewer.html --screenshot docs/img/viewer_traj1_case1.png",
    )),
    Picture("viewer_human_arm", "docs/pictures.md", (
        "mcdm-pin solve robots/human_arm.yaml -t reach_forward --case 3 -q --out out/human_reach_case3.npz",
        "mcdm-pin view robots/human_arm.yaml --results out/human_reach_case3.npz --time 1.0 "
        "--html out/human.html --screenshot docs/img/viewer_human_arm.png",
    )),
    Picture("viewer_neck", "docs/pictures.md", (
        "mcdm-pin solve robots/caspr/8S_neck/8S_neck.yaml -t roll --case 3 --cone all=15 -q "
        "--out out/neck_roll_case3.npz",
        "mcdm-pin view robots/caspr/8S_neck/8S_neck.yaml --results out/neck_roll_case3.npz --time 0.94 "
        "--html out/neck.html --screenshot docs/img/viewer_neck.png",
    )),
    Picture("viewer_cogiro", "docs/pictures.md", (
        "mcdm-pin solve robots/caspr/CoGiRo/CoGiRo.yaml -t general_1 --case 1 -q --out out/cogiro_case1.npz",
        "mcdm-pin view robots/caspr/CoGiRo/CoGiRo.yaml --results out/cogiro_case1.npz --time 2.0 "
        "--html out/cogiro.html --screenshot docs/img/viewer_cogiro.png",
    )),
    Picture("viewer_ipanema2", "docs/pictures.md", (
        "mcdm-pin solve robots/caspr/IPAnema_2/IPAnema_2.yaml -t traj_1 --case 1 -q --out out/ipanema2_case1.npz",
        "mcdm-pin view robots/caspr/IPAnema_2/IPAnema_2.yaml --results out/ipanema2_case1.npz --time 0.5 "
        "--html out/ipanema2.html --screenshot docs/img/viewer_ipanema2.png",
    )),
    Picture("workspace_cloud_two_link", "docs/workspace.md", (
        "mkdir -p out",
        "mcdm-pin workspace robots/two_link_sr.yaml --case 3 --cone shoulder=30 "
        "--grid q1_x=-3.1416:3.1416:49 --grid q4_x=-3.1416:3.1416:49 --chunk 100 --out out/arm.zarr",
        "mcdm-pin view robots/two_link_sr.yaml --workspace out/arm.zarr --frame link2 --color needed_cone_deg "
        "--html out/arm_cloud.html --screenshot docs/img/workspace_cloud_two_link.png",
    )),
    Picture("workspace_two_link_arm_case3", "README.md", (
        "mkdir -p out",
        "mcdm-pin workspace robots/two_link_sr.yaml --case 3 --cone shoulder=30 --chunk 100 "
        "--grid q1_x=-3.1416:3.1416:49 --grid q4_x=-3.1416:3.1416:49 --out out/arm_case3.zarr",
        "mcdm-pin plot out/arm_case3.zarr --out docs/img --prefix workspace_two_link_ --format png",
    )),
    Picture("scaling", "docs/speed.md", (
        "python benchmarks/scaling.py --peers all --warm-and-cold --plot docs/img/scaling.png --markdown docs/scaling.md",
    )),
    Picture("glenohumeral_abduction", "docs/glenohumeral.md", (
        "python tools/glenohumeral_study.py",
    )),
    Picture("rmr_closed_abd01", "docs/opensim.md", (  # needs RMR's folder in ../shared
        "PYTHONPATH=. python tools/rmr_study.py --json out.json --plot docs/img/rmr_closed_abd01.png",
    )),
    Picture("control_loop_cogiro", "docs/control.md", (
        "python benchmarks/control_loop.py --robots cogiro --duration 1 --plot docs/img/control_loop_cogiro.png",
    )),
)


def argv(command: str) -> list[str]:
    """The command as a process's arguments: ``mcdm-pin`` and ``python`` are this interpreter."""
    words = shlex.split(command)
    while "=" in words[0] and not words[0].startswith("-"):  # `PYTHONPATH=. python ...`: run() sets it
        words = words[1:]
    if words[0] == "mcdm-pin":
        return [sys.executable, "-m", "mcdm_pin", *words[1:]]
    if words[0] == "python":
        return [sys.executable, *words[1:]]
    return words


def run(picture: Picture) -> float:
    """Run ``picture``'s commands from the repository's root; the seconds it took."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(REPO), os.environ.get("PYTHONPATH", "")]))
    start = time.perf_counter()
    for command in picture.commands:
        words = shlex.split(command)
        if words[:2] == ["mkdir", "-p"]:
            (REPO / words[2]).mkdir(parents=True, exist_ok=True)
            continue
        if words[:2] == ["mcdm-pin", "workspace"]:  # a store is never overwritten: start afresh
            store = REPO / words[words.index("--out") + 1]
            if store.parts[-2:-1] == ("out",) and store.exists():
                shutil.rmtree(store)
        print("$", command, flush=True)
        subprocess.run(argv(command), cwd=REPO, env=env, check=True)
    return time.perf_counter() - start


def main(args=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("names", nargs="*", help="pictures to make (default: all), e.g. viewer_neck")
    p.add_argument("--list", action="store_true", help="print the pictures and their commands")
    a = p.parse_args(args)
    known = {pic.name: pic for pic in PICTURES}
    unknown = [n for n in a.names if n.removesuffix(".png") not in known]
    if unknown:
        p.error(f"unknown picture(s) {', '.join(unknown)}; known: {', '.join(known)}")
    chosen = [known[n.removesuffix(".png")] for n in a.names] or list(PICTURES)
    for pic in chosen:
        if a.list:
            print(f"docs/img/{pic.name}.png ({pic.doc}):\n  " + "\n  ".join(pic.commands))
            continue
        print(f"docs/img/{pic.name}.png: {run(pic):.1f} s", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())

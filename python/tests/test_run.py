"""Running the pipeline from Python: hocad.mesh_file writes what `hocad
mesh` writes; events reach the progress callable; a callable returning
True cancels with hocad.Interrupted, one raising cancels with its own
exception, Ctrl-C (SIGINT) cancels with KeyboardInterrupt; no output file
is left in any of these, and the library works on afterwards.
SPDX-License-Identifier: GPL-2.0-or-later
"""
import os
import signal
import subprocess
import sys
import textwrap

import pytest

import hocad

from conftest import SCREW

CLI = os.environ["HOCAD_CLI"]


def test_mesh_file_is_the_cli(tmp_path):
    out = tmp_path / "screw.msh"
    report = hocad.mesh_file(SCREW, output=out, order=2)
    table = hocad.format_table(report).splitlines()
    assert table[0].split()[:3] == ["stage", "order", "elements"]
    assert [line.split()[0] for line in table[1:4]] == ["linear", "high-order", "optimized"]
    assert table[4].startswith("optimized: ")
    assert "linear_mesh" not in report
    # the CLI's mesh of the same model and options is the same file
    cli_out = tmp_path / "cli.msh"
    subprocess.run([CLI, "mesh", SCREW, "--order", "2", "-o", str(cli_out), "-q"], check=True)
    assert cli_out.read_bytes() == out.read_bytes()


def test_events():
    events = []
    with hocad.Model(SCREW) as model:
        with model.mesh(order=3, progress=events.append) as mesh:
            report = mesh.report
    kinds = {e.kind for e in events}
    assert {"progress", "stage", "iteration"} <= kinds
    assert kinds <= {"progress", "stage", "iteration", "repair", "note", "warning", "check"}
    stages = [e.stage for e in events if e.kind == "stage"]
    assert [s["name"] for s in stages] == [s["name"] for s in report["stages"]]
    for got, want in zip(stages, report["stages"]):
        for key in ("elements", "order", "min", "max", "mean", "tangled"):
            assert got[key] == want[key]
    sweeps = [e.iteration for e in events if e.kind == "iteration"]
    assert [s["iteration"] for s in sweeps] == list(range(1, len(sweeps) + 1))
    assert len(sweeps) == report["stages"][-1]["iterations"]
    assert all(isinstance(e.message, str) and e.message for e in events)


@pytest.mark.parametrize("when", ["progress", "stage", "iteration"])
def test_callback_cancels(tmp_path, when):
    out = tmp_path / "cancelled.msh"
    seen = []

    def progress(event):
        seen.append(event.kind)
        return event.kind == when

    with pytest.raises(hocad.Interrupted) as info:
        hocad.mesh_file(SCREW, output=out, order=3, progress=progress)
    assert info.value.status == hocad.ERR_INTERRUPTED
    assert seen[-1] == when
    assert not out.exists()
    assert os.listdir(tmp_path) == []
    # the library works on
    assert hocad.mesh_file(SCREW, order=1)["stages"][0]["name"] == "linear"


def test_callback_exception_cancels(tmp_path):
    class Stop(Exception):
        pass

    def progress(event):
        if event.kind == "iteration":
            raise Stop("from the callback")

    out = tmp_path / "cancelled.msh"
    with pytest.raises(Stop, match="from the callback"):
        hocad.mesh_file(SCREW, output=out, order=2, progress=progress)
    assert not out.exists()


def test_optimize_and_linear_cancel():
    with hocad.Model(SCREW) as model:
        with model.mesh(order=3, optimize=False) as mesh:
            with pytest.raises(hocad.Interrupted):
                mesh.optimize(progress=lambda e: True)
            with pytest.raises(hocad.Interrupted):
                mesh.repair(progress=lambda e: e.kind == "iteration")
        fractions = []
        with model.linear_mesh(progress=lambda e: fractions.append(e.value)) as linear:
            assert linear.order == 1
        assert fractions and all(0 <= f <= 1 for f in fractions)
        with pytest.raises(hocad.Interrupted):
            model.linear_mesh(progress=lambda e: True)


SIGINT_SCRIPT = textwrap.dedent("""
    import sys, time
    import hocad
    model, out = sys.argv[1], sys.argv[2]
    started = False
    def progress(event):
        global started
        if event.kind == "iteration" and not started:
            started = True
            print("started", flush=True)
            time.sleep(30)  # the parent's SIGINT ends this sleep
    try:
        hocad.mesh_file(model, output=out, order=3, progress=progress)
    except KeyboardInterrupt:
        print("KeyboardInterrupt", flush=True)
    else:
        sys.exit("not interrupted")
    # the library works on after the interruption
    report = hocad.mesh_file(model, output=out, order=2)
    print("again", report["stages"][-1]["tangled"], flush=True)
""")


def test_ctrl_c(tmp_path):
    out = tmp_path / "interrupted.msh"
    proc = subprocess.Popen([sys.executable, "-c", SIGINT_SCRIPT, SCREW, str(out)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert proc.stdout.readline().strip() == "started"
        assert not out.exists()
        proc.send_signal(signal.SIGINT)
        assert proc.stdout.readline().strip() == "KeyboardInterrupt"
        assert not out.exists() and os.listdir(tmp_path) == []
        stdout, stderr = proc.communicate(timeout=300)
    finally:
        proc.kill()
        proc.wait()
    assert proc.returncode == 0, stderr
    assert stdout.strip() == "again 0"
    assert os.listdir(tmp_path) == ["interrupted.msh"]

"""The commands at the door (issue 9): --out checked before computing, memory estimates,
negative loads, bad options as one line, a load beyond the branch, Ctrl-C during an ensemble,
progress on a pipe and on a terminal, and a light start. The refusals run in this interpreter
(commandline.run_main); whole runs and Ctrl-C run the command in a fresh one (slow)."""
from __future__ import annotations

import io
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from commandline import ROOT, error_line, run_cli, run_main

FOUR = "[disks]\nN = 4\n[load]\nF_x = [0.0, 0.05]\n"
"""A small scene: every command on it takes a second or two."""

COMMANDS = {
    "bifurcate": [],
    "simulate": ["--fx", "0.01", "--t-end", "1"],
    "verify": ["--t-end", "1"],
    "map": ["--vary", "contacts.mu=5:10:2"],
    "report": ["--only", "fig6"],
}


def scene_file(tmp_path: Path, text: str = FOUR, name: str = "four.toml") -> str:
    path = tmp_path / name
    path.write_text(text)
    return str(path)


def one_line(result: subprocess.CompletedProcess, command: str, code: int = 2) -> str:
    """The refusal of bad input: exit `code`, exactly one line on stderr (so nothing was
    computed: no progress stage started), no traceback. The refusals below run in this
    interpreter (commandline.run_main); test_a_refusal_is_the_same_in_a_fresh_interpreter
    runs one for each command end to end."""
    assert result.returncode == code, result.stderr
    assert result.stderr.count("\n") == 1, result.stderr
    return error_line(result, command)



def test_run_main_ends_as_the_interpreter_would_and_leaves_this_one_as_it_was(tmp_path):
    """commandline.run_main: --version exits 0 with its line on stdout, a usage error (argparse's
    SystemExit) 2 with one line; a relative scene path is read in `cwd`; afterwards the working
    directory and os.environ are this process's again."""
    version = run_main("--version")
    assert version.returncode == 0 and version.stdout.startswith("diskfriction ")
    assert version.stderr == ""
    usage = run_main("scene", "a.toml", "b.toml")
    assert usage.returncode == 2 and usage.stdout == "" and usage.stderr.count("\n") == 1
    assert usage.stderr.startswith("diskfriction: error: unrecognized arguments: b.toml")
    (tmp_path / "here.toml").write_text("[disks]\nN = 5\n")
    cwd, env = os.getcwd(), dict(os.environ)
    scene = run_main("scene", "here.toml", cwd=tmp_path, env={"DISKFRICTION_RUN_MAIN_TEST": "1"})
    assert scene.returncode == 0 and "N = 5" in scene.stdout and 'name = "here"' in scene.stdout
    assert os.getcwd() == cwd and dict(os.environ) == env

# ---- --out, checked before anything is computed -------------------------------------------

def bad_outs(tmp_path: Path) -> dict[str, str]:
    (tmp_path / "a-file").write_text("")
    return {"existing file": str(tmp_path / "a-file"),
            "under a file": str(tmp_path / "a-file" / "out"),
            "in /proc": "/proc/diskfriction-out",
            "empty": ""}


@pytest.mark.parametrize("command", COMMANDS)
@pytest.mark.parametrize("case", ["existing file", "under a file", "in /proc", "empty"])
def test_an_unusable_out_is_one_line_and_exit_2_before_computing(tmp_path, command, case):
    out = bad_outs(tmp_path)[case]
    result = run_main(command, scene_file(tmp_path), *COMMANDS[command], "--out", out)
    assert "--out" in one_line(result, command)


@pytest.mark.parametrize("command", COMMANDS)
def test_a_refusal_is_the_same_in_a_fresh_interpreter(tmp_path, command):
    """End to end, `python -m diskfriction COMMAND SCENE --out A-FILE`: exit 2 and one line,
    the same bytes as in this interpreter (run_main, which the other refusals here use)."""
    out = bad_outs(tmp_path)["existing file"]
    fresh = run_cli(command, scene_file(tmp_path), *COMMANDS[command], "--out", out)
    assert "--out: not a directory" in one_line(fresh, command)
    here = run_main(command, scene_file(tmp_path), *COMMANDS[command], "--out", out)
    assert (here.returncode, here.stdout, here.stderr) == (fresh.returncode, fresh.stdout, fresh.stderr)


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes into a read-only directory anyway")
def test_a_read_only_out_is_one_line_and_exit_2(tmp_path):
    locked = tmp_path / "locked"
    locked.mkdir(mode=0o555)
    result = run_main("bifurcate", scene_file(tmp_path), "--out", str(locked / "out"))
    assert "cannot write there" in one_line(result, "bifurcate")


# ---- memory ---------------------------------------------------------------------------------

@pytest.mark.parametrize("N, eps", [(100_000, 1e-4), (10**12, 0.0)])
@pytest.mark.parametrize("command", COMMANDS)
def test_a_scene_too_large_for_this_machine_is_refused_with_one_line(tmp_path, command, N, eps):
    """Pre-compressed (eps > 0: dense spectra) at N = 100 000, or any scene at N = 10^12."""
    scene = scene_file(tmp_path, f"[disks]\nN = {N}\neps = {eps}\n")
    result = run_main(command, scene, *COMMANDS[command], "--out", str(tmp_path / "out"))
    line = one_line(result, command)
    assert f"N = {N}" in line and "more than this machine's" in line


def test_the_memory_guard_counts_the_scan_workers(tmp_path):
    """The sweep's dense matrices are formed in its process and in each scan worker: at an N
    whose sweep fits in one process but not in three, check_memory refuses two workers
    (one line naming the three processes) and lets one process go, and three without dense
    matrices (eps = 0); `bifurcate` with its default workers refuses the pre-compressed
    scene, exit 2."""
    from diskfriction.cli.common import CommandError, check_memory
    from diskfriction.models.chain.memory import sweep_bytes
    from diskfriction.continuation.detection.collisions import DetectionParams
    from diskfriction.continuation.detection.scans import planned_workers
    from diskfriction.memory import physical_memory
    from diskfriction.scenes import Scene

    have, N = physical_memory(), 100
    while sweep_bytes(Scene(N=N).ndof, processes=3) <= have:
        N = int(N * 1.2)
    scene = Scene(N=N, eps=1e-4)  # pre-compressed: every disk in the chain, dense spectra
    assert sweep_bytes(scene.ndof, processes=1) < have
    check_memory("bifurcate", scene, processes=1)
    with pytest.raises(CommandError, match="in 3 processes"):
        check_memory("bifurcate", scene, processes=3)
    check_memory("bifurcate", Scene(N=N), processes=3, dense=False)  # eps = 0: free disks
    if planned_workers(scene.ndof, DetectionParams()) == 2:
        result = run_main("bifurcate", scene_file(tmp_path, f"[disks]\nN = {N}\neps = 1e-4\n"),
                          "--out", str(tmp_path / "out"))
        assert "in 3 processes" in one_line(result, "bifurcate")


NEEDS = {"bifurcate": "a sweep's points of 300000 unknowns",
         "simulate": "the dense 300000 x 300000 spectrum at a run's start",
         "verify": "the dense 300000 x 300000 spectrum at a run's start"}


@pytest.mark.parametrize("command", sorted(NEEDS))
def test_each_command_names_what_its_memory_estimate_counts(tmp_path, command):
    """The paper's eps = 0 at N = 100 000 (issue 23: bifurcate said 38.4 GB, simulate 8.68e3
    GB "for a sweep of dense matrices", which simulate never forms): bifurcate's sweep forms
    no dense matrix at eps = 0, while simulate and verify take a dense spectrum at a run's
    start; each line says which it counted, and the same need gives the same figure."""
    scene = scene_file(tmp_path, "[disks]\nN = 100000\n")
    result = run_main(command, scene, *COMMANDS[command], "--out", str(tmp_path / "out"))
    line = one_line(result, command)
    assert f"N = 100000: {NEEDS[command]} needs about " in line
    if command != "bifurcate":
        assert "needs about 4.32e+03 GB" in line


def test_counts_agree_with_their_nouns():
    from diskfriction.words import count

    assert [count(1, "collision"), count(2, "collision"), count(0, "window")] == [
        "1 collision", "2 collisions", "0 windows"]
    assert [count(1, "equilibrium", "equilibria"), count(3, "equilibrium", "equilibria")] == [
        "1 equilibrium", "3 equilibria"]


def test_the_scene_command_shows_a_large_scene(tmp_path):
    """A scene is a description: `scene` prints it whatever its size; commands refuse it."""
    result = run_main("scene", scene_file(tmp_path, "[disks]\nN = 1000000000000\n"))
    assert result.returncode == 0 and "N = 1000000000000" in result.stdout


@pytest.mark.slow
def test_a_run_whose_frames_exceed_the_memory_is_refused(tmp_path):
    result = run_main("simulate", scene_file(tmp_path), "--fx", "0.01", "--t-end", "1e15",
                      "--out", str(tmp_path / "out"))
    assert result.returncode == 2
    assert "frames" in error_line(result, "simulate")
    assert not list((tmp_path / "out").iterdir())


# ---- bad options ------------------------------------------------------------------------------

BAD = [
    (["verify", "--amplitude", "-1"], "--amplitude"),
    (["simulate", "--fx", "0.01,0.02", "--t-end", "1", "--scheduler", "garbage"], "--scheduler"),
    (["report", "--only", ""], "--only"),
    (["report", "--only", ","], "--only"),
    (["simulate", "--fx", "0.01", "--t-end", "1", "--dt", "2"], "--dt"),
    (["simulate", "--fx", "0.083,0.083", "--t-end", "1"], "given twice"),
    (["simulate", "--fx", "0.03", "--t-end", "1", "--seed=-3"], "--seed: must be an integer >= 0 (got -3)"),
    (["simulate", "--fx", "-0.083", "--t-end", "1"], "mirror image"),
    (["bifurcate", "--fx=-0.1:0"], "mirror image"),
]


@pytest.mark.parametrize("args, says", BAD, ids=[" ".join(a) for a, _ in BAD])
def test_bad_option_is_one_line_and_exit_2(tmp_path, args, says):
    result = run_main(*args, "--out", str(tmp_path / "out"))
    assert says in one_line(result, args[0])


def test_a_negative_load_in_a_scene_is_refused_for_the_same_reason(tmp_path):
    scene = scene_file(tmp_path, "[load]\nF_x = [-0.12, 0.0]\n")
    for command in ("scene", "bifurcate"):
        result = run_main(command, scene)
        assert result.returncode == 2 and "mirror image" in result.stderr
        assert result.stderr.count("\n") == 1


@pytest.mark.slow
def test_a_step_beyond_the_stability_limit_or_an_unresolved_run_is_not_reported(tmp_path):
    """Issue 23: --dt 0.2 at F_x = 0.03 once reported "slid: True" with max M = 1e11. A step
    not below 2 / omega_max is refused (exit 2, the option named); one below it whose run goes
    unstable writes its files for inspection, reports no "slid" and exits 1."""
    out = tmp_path / "out"
    beyond = run_cli("simulate", "--fx", "0.03", "--t-end", "300", "--dt", "0.2", "--out", str(out))
    assert beyond.returncode == 2 and "slid" not in beyond.stdout
    line = error_line(beyond, "simulate")
    assert "--dt" in line and "stability limit 2 / omega_max = 0.1366" in line and "0.2" in line
    unresolved = run_cli("simulate", "--fx", "0.03", "--t-end", "300", "--dt", "0.13", "--out", str(out))
    assert unresolved.returncode == 1 and "slid: True" not in unresolved.stdout
    assert "simulate: run to t = 300: 2308 steps, about " in unresolved.stderr  # an estimate first
    assert "energy budget" in error_line(unresolved, "simulate")
    summary = json.loads((out / "summary.json").read_text())
    assert summary["accurate"] is False and summary["slid"] is None


# ---- a load beyond the branch from rest -------------------------------------------------------

SHORT = "[disks]\nN = 4\n[contacts]\nmu = 1.0\n"
"""A scene whose branch from rest ends early (at F_x ~ 3e-5: the continuation turns back), far
below the substrate's limit N mu F_y = 0.4: a quick case of a load beyond the branch."""


@pytest.mark.slow
def test_simulate_beyond_the_end_of_the_branch_says_where_and_why(tmp_path):
    """Nothing may be written or reported for the load asked for."""
    out = tmp_path / "out"
    result = run_cli("simulate", scene_file(tmp_path, SHORT), "--fx", "0.2", "--t-end", "10",
                     "--out", str(out))
    assert result.returncode == 1
    line = error_line(result, "simulate")
    assert "no equilibrium beyond F_x = " in line and "(asked for 0.2)" in line
    assert 0 < float(line.split("beyond F_x = ")[1].split()[0]) < 0.2
    assert "; there " in line  # the contacts of the last point
    assert result.stdout == "" and not list(out.iterdir())


@pytest.mark.slow
def test_verify_of_a_branch_ending_short_of_the_scenes_range_says_where_and_why(tmp_path):
    """verify's windows are those of the branch up to the scene's F_x range end: a branch that
    ends before it is one line and exit 1, not a table of the windows it happened to reach."""
    out = tmp_path / "out"
    result = run_cli("verify", scene_file(tmp_path, SHORT), "--t-end", "10", "--out", str(out))
    assert result.returncode == 1
    line = error_line(result, "verify")
    assert "no equilibrium beyond F_x = " in line and "(asked for 0.12)" in line
    assert result.stdout == "" and not (out / "verify.json").exists()


@pytest.mark.slow
def test_equilibrium_at_ends_exactly_on_the_load_or_raises():
    from diskfriction.models.chain.equilibrium import NoEquilibrium, equilibrium_at
    from diskfriction.scenes import Scene
    from diskfriction.symbolic import System

    system = System.from_scene(Scene(N=3))
    eq = equilibrium_at(system, 0.0123456789)
    assert eq.F_x == 0.0123456789 and eq.residual <= 1e-10
    assert abs(system.forces(eq.q, eq.xi, eq.F_x)).max() <= 1e-10
    rest = equilibrium_at(system, 0.0)
    assert rest.F_x == 0.0 and (rest.q == system.rest_state()[0]).all()
    short = System.from_scene(Scene(N=4, mu=1.0))
    with pytest.raises(NoEquilibrium) as raised:
        equilibrium_at(short, 0.2)
    assert raised.value.F_x == 0.2 and 0 < raised.value.F_end < 0.2
    assert "\n" not in str(raised.value)
    with pytest.raises(ValueError):
        equilibrium_at(system, -0.01)


def test_the_last_point_names_contacts_at_the_coulomb_limit_and_open_ones():
    """At rest every pair touches at delta = 0 (open: inactive); put the substrate histories
    of disks 1 and 2 exactly at their Coulomb limit t* = mu k_n delta_w / k_t."""
    from diskfriction.models.chain.equilibrium import contact_states
    from diskfriction.scenes import Scene
    from diskfriction.symbolic import System

    scene = Scene(N=3)
    system = System.from_scene(scene)
    q, xi = system.rest_state()
    xi[3:5] = [scene.mu * scene.k_n * scene.delta_w0 / scene.k_t, -scene.mu * scene.k_n
               * scene.delta_w0 / scene.k_t]
    assert contact_states(system, q, xi) == ("the substrate contacts of disks 1, 2 are at the "
                                             "Coulomb limit (mu = 10), pairs 1-2, 2-3, 3-1 "
                                             "are open")
    xi[4] *= 0.5
    assert contact_states(system, q, xi).startswith("the substrate contact of disk 1 is at")


def test_disk_lists_shorten_runs():
    from diskfriction.models.chain.equilibrium import disk_list

    assert disk_list([1, 2, 3, 4, 5, 6, 7, 9]) == "1..7, 9"
    assert disk_list([2, 3, 7]) == "2, 3, 7"


# ---- Ctrl-C during an ensemble ------------------------------------------------------------------

def ignores_sigint(pid: int) -> bool:
    """Whether process `pid` ignores SIGINT (its SigIgn mask in /proc, Linux)."""
    status = Path(f"/proc/{pid}/status").read_text()
    mask = int(next(line.split()[1] for line in status.splitlines() if line.startswith("SigIgn:")), 16)
    return bool(mask & (1 << (signal.SIGINT - 1)))


def default_sigint() -> None:
    """SIGINT at its default in the command, as in a terminal's foreground job: a suite
    started in the background by a non-interactive shell inherits SIG_IGN for it, which the
    command (Python) would keep, and no Ctrl-C could reach it."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


@pytest.mark.slow
def test_interrupting_an_ensemble_prints_one_line_and_exits_130(tmp_path):
    """As a terminal does: SIGINT to the whole process group, once the dask workers run. The
    workers ignore it (else each may print a KeyboardInterrupt traceback while the parent
    shuts them down, depending on what it is doing at that moment)."""
    import psutil

    proc = subprocess.Popen(
        [sys.executable, "-m", "diskfriction", "simulate", "--fx", "0.083", "--realizations",
         "2", "--t-end", "1e6", "--out", str(tmp_path / "out")],
        cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        start_new_session=True, preexec_fn=default_sigint)
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline and proc.poll() is None:
            workers = [c for c in psutil.Process(proc.pid).children(recursive=True)
                       if "spawn_main" in " ".join(c.cmdline())]
            if workers:
                break
            time.sleep(0.2)
        assert workers and all(ignores_sigint(w.pid) for w in workers)
        time.sleep(1.5)  # the workers start and take their realizations
        err = "still running after 12 SIGINTs, 10 s apart"
        for _ in range(12):  # as a user would, press again if it came while the cluster started
            os.killpg(proc.pid, signal.SIGINT)
            try:
                out, err = proc.communicate(timeout=10)
                break
            except subprocess.TimeoutExpired:
                continue
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    assert proc.returncode == 130, err
    lines = err.splitlines()
    assert lines[-1] == (f"interrupted: the finished realizations are kept in {tmp_path / 'out' / 'runs'}; "
                         f"rerun the same command to resume")
    assert all(line.startswith("simulate: ") for line in lines[:-1]), err
    assert "Traceback" not in err


@pytest.mark.slow
def test_interrupting_a_sweep_with_scan_workers_prints_one_line_and_exits_130(tmp_path):
    """N = 100 scans its steps on 2 forked workers (continuation/detection/scans.py): they ignore SIGINT,
    the command ends them and says one line."""
    import psutil

    scene = tmp_path / "n100.toml"
    scene.write_text("[disks]\nN = 100\neps = 1e-4\n")
    proc = subprocess.Popen(
        [sys.executable, "-m", "diskfriction", "bifurcate", str(scene), "--workers", "2", "--out",
         str(tmp_path / "out")],
        cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        start_new_session=True, preexec_fn=default_sigint)
    try:
        deadline, workers = time.monotonic() + 120, []
        while time.monotonic() < deadline and proc.poll() is None and len(workers) < 2:
            workers = psutil.Process(proc.pid).children()
            time.sleep(0.1)
        assert len(workers) == 2 and all(ignores_sigint(w.pid) for w in workers)
        time.sleep(1.0)  # scans under way
        os.killpg(proc.pid, signal.SIGINT)
        out, err = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    assert proc.returncode == 130, err
    # bifurcate does not resume: it must not promise that a rerun does (issue 23)
    assert err.splitlines()[-1] == "interrupted: bifurcate does not resume; run it again to get its results"
    assert "Traceback" not in err
    assert not any(w.is_running() and w.status() != psutil.STATUS_ZOMBIE for w in workers)


# ---- progress -----------------------------------------------------------------------------------

class Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_progress_is_a_line_per_stage_off_a_terminal_and_a_bar_on_one():
    from diskfriction.cli.progress import Progress

    piped = io.StringIO()
    p = Progress("bifurcate", stream=piped)
    report = p.part("kernels")
    report("generating", 0.0)
    report("generating", 0.5)
    report("compiling", None)
    p.stage("sweep")
    p(0.5, "F_x = 0.06")
    p.close()
    assert piped.getvalue().splitlines() == ["bifurcate: kernels: generating",
                                             "bifurcate: kernels: compiling", "bifurcate: sweep"]
    tty = Terminal()
    p = Progress("bifurcate", stream=tty)
    p.stage("sweep")
    p(0.5, "F_x = 0.06")
    p.close()
    text = tty.getvalue()
    assert "\n" not in text and "[###############...............]  50.0% F_x = 0.06" in text
    assert text.endswith("\r\x1b[K")  # the status line is cleared at the end


def test_the_scene_command_imports_no_numerical_library():
    code = ("import sys, io, contextlib\nfrom diskfriction.cli.main import main\n"
            "with contextlib.redirect_stdout(io.StringIO()): main(['scene'])\n"
            "print(sorted(m for m in ('numpy', 'scipy', 'numba', 'matplotlib', 'dask', 'sympy')"
            " if m in sys.modules))")
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert run.stdout.strip() == "[]", run.stderr


@pytest.mark.parametrize("ctrl_c", [True, False])
def test_ctrl_c_swallowed_by_a_library_still_ends_the_command_as_ctrl_c(ctrl_c, capsys):
    """numba, interrupted while it saves a compiled function to its cache, swallows the
    KeyboardInterrupt and fails later with a RuntimeError that does not chain to it: the command
    still ends as Ctrl-C does (one line, 130). Without a Ctrl-C that error is not one."""
    import argparse

    from diskfriction.cli.common import EXIT_INTERRUPTED, run_command

    def run(args):
        if ctrl_c:
            try:
                os.kill(os.getpid(), signal.SIGINT)
                time.sleep(1.0)  # the handler runs here
            except KeyboardInterrupt:
                pass  # swallowed, as numba's cache save does
        raise RuntimeError("no compiled object yet")

    args = argparse.Namespace(command="bifurcate", run=run)
    if not ctrl_c:
        with pytest.raises(RuntimeError):
            run_command(args)
        return
    assert run_command(args) == EXIT_INTERRUPTED
    assert capsys.readouterr().err.startswith("interrupted: bifurcate does not resume")
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler

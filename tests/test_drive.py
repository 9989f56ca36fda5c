"""``phantom-cad drive`` end to end on the simulated bus (phantom_cad/drive/simbus.py: a
pseudo-terminal answering the Feetech protocol as six servos would): scan, zero, move, pose and
sweep through the command line; each fault (a missing servo, a timeout, a corrupt checksum, a servo
reporting overload) one ``error:`` line and exit 2, and a sweep stopped by one writes nothing; the
sweep loads in compare and diagnose; and no command sequence puts a servo's goal outside its travel."""

from __future__ import annotations

import math
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from phantom_cad import load_hand
from phantom_cad import postures as P
from phantom_cad.calibration.data import read_measurements, write_table
from phantom_cad.cli import main
from phantom_cad.drive.bus import Bus
from phantom_cad.drive.driver import Driver, family_of, read_zero
from phantom_cad.drive import protocol as P_
from phantom_cad.drive.protocol import DriveError
from phantom_cad.drive.simbus import Fault, SimBus
from phantom_cad.kinematics.topology import Q_COLUMNS, SERVOS
from phantom_cad.units import DEG

HAND = load_hand()
FAMILY = family_of(HAND.params)[1]
RES = FAMILY.span_deg * DEG / FAMILY.counts     # rad per count, from the catalogue
#: the servo the tests single out, by its label
U3 = next(s for s in SERVOS if s.label == "u3")
FAST = "600"                                    # deg/s: the SCS0009's rated speed, the tests' ramps


#: ms: the simulated servos answer within a millisecond, but a loaded test machine may delay its thread
TIMEOUT = "1000"


def run(argv, capsys):
    argv = [str(a) for a in argv]
    if argv[0] == "drive" and "--port" in argv and "--timeout" not in argv:
        argv[2:2] = ["--timeout", TIMEOUT]
    with pytest.raises(SystemExit) as exit_:
        main(argv)
    cap = capsys.readouterr()
    return exit_.value.code, cap.out, cap.err


@pytest.fixture
def bus():
    with SimBus(FAMILY) as sim:
        yield sim


@pytest.fixture
def zeroed(bus, tmp_path, capsys):
    """The simulated hand zeroed: (sim, zero file)."""
    path = tmp_path / "zero.json"
    code, out, err = run(["drive", "zero", "--port", bus.port, "--zero", path], capsys)
    assert (code, err) == (0, ""), err
    return bus, path


def eventually(condition, within: float = 2.0) -> bool:
    """Whether ``condition()`` holds within ``within`` seconds: a broadcast packet has no answer, so
    the command returns before the simulated bus's thread has taken it."""
    deadline = time.monotonic() + within
    while not condition():
        if time.monotonic() > deadline:
            return False
        time.sleep(0.01)
    return True


def in_travel(sim, zero) -> bool:
    """Every goal each simulated servo was given, as an angle, inside its servo's travel."""
    for s in SERVOS:
        goals = np.array(sim.servo(s.bus_id).goals, float)
        u = zero.signs[s.index] * (goals - zero.counts[s.index]) * RES
        if goals.size and not ((u >= HAND.u_min[s.index] - 1e-12) & (u <= HAND.u_max[s.index] + 1e-12)).all():
            return False
    return True


def test_scan_finds_the_six_servos(bus, capsys):
    code, out, err = run(["drive", "scan", "--port", bus.port, "--max-id", "7", "--timeout", "200"], capsys)
    assert code == 0 and err == ""
    for s in SERVOS:
        assert f"ID {s.bus_id:3d}  model 9  firmware 3.10  position {FAMILY.counts // 2:4d}  {s.label}" in out
    assert "all 6 servos answer" in out


@pytest.mark.slow
def test_zero_move_pose_sweep(zeroed, tmp_path, capsys):
    sim, zero_file = zeroed
    zero = read_zero(zero_file)
    # the servos were at the middle of their counts when zeroed (the simulated servos start there)
    assert zero.counts == (FAMILY.counts // 2,) * 6 and zero.signs == (1,) * 6
    # the zero wrote each servo's travel as its angle limits
    s3 = sim.servo(U3.bus_id)
    limit = P_.unword(s3.mem[s3.table.max_angle:s3.table.max_angle + 2], FAMILY.big_endian)
    assert limit == FAMILY.counts // 2 + math.floor(HAND.u_max[U3.index] / RES)

    target = [5.0, 10.0, 20.0, 30.0, 40.0, 50.0]
    code, out, err = run(["drive", "move", "--port", sim.port, "--zero", zero_file, "--degrees", "--speed", FAST,
                          "--", *target], capsys)
    assert code == 0 and err == ""
    got = np.array([sim.servo(s.bus_id).goals[-1] for s in SERVOS]) - zero.counts
    assert np.allclose(got * RES, np.radians(target), atol=RES / 2 + 1e-12)

    # torque off: limp, the goals as they were; on: held where they are
    for state in ("off", "on"):
        code, out, err = run(["drive", "torque", state, "--port", sim.port, "--zero", zero_file], capsys)
        assert (code, err) == (0, "")
        assert eventually(lambda: all(s.mem[s.table.torque_enable] == (state == "on") for s in sim.servos))
    held = np.array([sim.servo(s.bus_id).goals[-1] for s in SERVOS]) - zero.counts
    assert np.allclose(held * RES, np.radians(target), atol=1.5 * RES)

    library = P.load(HAND)
    code, out, err = run(["drive", "pose", "fist", "--port", sim.port, "--zero", zero_file, "--speed", FAST], capsys)
    assert code == 0 and err == ""
    u = P.pose(HAND, library["fist"]).u
    got = np.array([sim.servo(s.bus_id).goals[-1] for s in SERVOS]) - zero.counts
    # each angle to the nearest count, kept inside the counts of the travel (the fist ends it)
    lo, hi = np.ceil(HAND.u_min / RES - 1e-9), np.floor(HAND.u_max / RES + 1e-9)
    assert np.array_equal(got, np.clip(np.rint(u / RES), lo, hi))

    out_csv = tmp_path / "sweep.csv"
    code, out, err = run(["drive", "sweep", "--out", out_csv, "--port", sim.port, "--zero", zero_file,
                          "--speed", FAST], capsys)
    assert code == 0 and err == "", err
    m = read_measurements(out_csv)
    assert m.sweep_ids == tuple(s.label for s in SERVOS) and m.measured.all() and np.isnan(m.q).all()
    assert np.all(np.diff(m.t) > 0)
    for s in SERVOS:    # each sweep moves its own servo over the travel, up then down, the others at rest
        rows = m.sweep == s.index
        assert m.u[rows, s.index].max() == pytest.approx(HAND.u_max[s.index], abs=2 * RES)
        assert m.u[rows, s.index][-1] == pytest.approx(HAND.u_min[s.index], abs=2 * RES)
        assert np.abs(np.delete(m.u[rows], s.index, axis=1) - np.delete(HAND.u_min, s.index)).max() < 2 * RES
    assert in_travel(sim, zero)

    # the sweep alone has no joint angle to compare with: compare says so
    code, out, err = run(["compare", out_csv], capsys)
    assert code == 2 and "no joint angle was measured" in err and err.count("\n") == 1

    # the camera's angles (here the model's) merged by time, then compare and diagnose read it as it is
    cam = tmp_path / "camera.csv"
    q = HAND.forward(m.u, compensated=True)
    # the camera's frames half-way between the sweep's samples, plus one at its first sample: linear
    # interpolation back at the samples is the mean of the two frames around each
    t_cam = np.concatenate([m.t[:1], (m.t[1:] + m.t[:-1]) / 2, m.t[-1:] + 1.0])
    q_cam = np.concatenate([q[:1], (q[1:] + q[:-1]) / 2, q[-1:]])
    write_table(cam, {"t": t_cam, **{c: q_cam[:, j] for j, c in enumerate(Q_COLUMNS)}})
    merged = tmp_path / "merged.csv"
    code, out, err = run(["drive", "merge", "--sweep", out_csv, "--angles", cam, "--out", merged], capsys)
    assert code == 0, err
    mm = read_measurements(merged)
    assert mm.q_columns == Q_COLUMNS
    w = (m.t[1:-1] - t_cam[1:-2]) / (t_cam[2:-1] - t_cam[1:-2])
    expect = q_cam[1:-2] + w[:, None] * (q_cam[2:-1] - q_cam[1:-2])
    assert np.allclose(mm.q[1:-1], expect, atol=1e-9) and np.allclose(mm.q[0], q[0], atol=1e-12)
    code, out, err = run(["compare", merged], capsys)
    assert code == 0, err
    code, out, err = run(["diagnose", merged], capsys)
    assert code == 0, err


def test_a_command_outside_the_travel_is_refused(zeroed, capsys):
    sim, zero_file = zeroed
    code, out, err = run(["drive", "move", "--port", sim.port, "--zero", zero_file, "--degrees",
                          "--", 0, 0, 120, 0, 0, 0], capsys)
    assert code == 2 and err.count("\n") == 1 and err.startswith("error: servo u3: 120.00 deg is outside its travel")
    assert all(not s.goals for s in sim.servos)
    code, out, err = run(["drive", "move", "--port", sim.port, "--zero", zero_file, "--degrees", "--clip",
                          "--speed", FAST, "--", 0, 0, 120, 0, 0, 0], capsys)
    assert code == 0
    assert sim.servo(U3.bus_id).goals[-1] == FAMILY.counts // 2 + math.floor(HAND.u_max[U3.index] / RES)


FAULTS = {"missing": "no answer", "timeout": "no answer", "checksum": "corrupt status packet",
          "overload": "reports overload"}


@pytest.mark.parametrize("kind", sorted(FAULTS))
def test_each_fault_is_one_error_line_and_a_sweep_writes_nothing(zeroed, tmp_path, capsys, kind):
    sim, zero_file = zeroed
    # after the zero: a missing servo from the first packet; the others part way through the sweep
    sim.faults.append(Fault(kind, 4, after=sim.servo(4).seen + (0 if kind == "missing" else 40)))
    out_csv = tmp_path / "sweep.csv"
    code, out, err = run(["drive", "sweep", "--out", out_csv, "--port", sim.port, "--zero", zero_file,
                          "--speed", FAST], capsys)
    assert code == 2 and err.count("\n") == 1, err
    assert err.startswith("error: servo u4 (ID 4) on ") and FAULTS[kind] in err
    assert "Traceback" not in err
    assert not out_csv.exists() and not list(tmp_path.glob(".sweep.csv*"))
    if kind == "missing":
        assert all(not s.goals for s in sim.servos)        # nothing was moved
    if kind == "overload":
        assert "torque off on every servo" in err
        assert eventually(lambda: all(s.mem[s.table.torque_enable] == 0 for s in sim.servos))
    elif kind != "missing":
        assert "hold their last goal" in err
    assert in_travel(sim, read_zero(zero_file))


def test_no_port_is_one_error_line(tmp_path, capsys):
    code, out, err = run(["drive", "scan", "--port", tmp_path / "ttyNONE"], capsys)
    assert code == 2 and err.count("\n") == 1 and err.startswith(f"error: port {tmp_path / 'ttyNONE'}: cannot be opened")
    code, out, err = run(["drive", "scan"], capsys)
    assert code == 2 and "--port" in err
    code, out, err = run(["drive", "scan", "--port", tmp_path, "--timeout", "0"], capsys)
    assert code == 2 and err == "error: --timeout 0: must be a positive number of milliseconds\n"


POSES = {n: P.pose(HAND, p).u for n, p in P.load(HAND).items() if n in ("fist", "two", "opposition_index")}
angle = st.one_of(st.floats(-4.0, 4.0), st.just(math.nan), st.just(math.inf), st.floats(-1.0, 2.0))
command = st.one_of(st.tuples(st.just("move"), st.lists(angle, min_size=6, max_size=6), st.booleans()),
                    st.tuples(st.just("pose"), st.sampled_from(sorted(POSES)), st.just(False)),
                    st.tuples(st.just("hold"), st.none(), st.just(False)))


@pytest.mark.slow
@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.lists(command, min_size=1, max_size=4))
def test_no_command_sequence_drives_a_servo_outside_its_travel(zeroed, commands):
    sim, zero_file = zeroed
    zero = read_zero(zero_file)
    with Bus(sim.port, FAMILY.baud, FAMILY.big_endian, float(TIMEOUT) / 1e3) as b:
        d = Driver(b, HAND, zero)
        for kind, value, clip in commands:
            if kind == "hold":
                d.hold(d.speed(600.0))
                continue
            u = POSES[value] if kind == "pose" else value
            try:
                d.move(u, d.speed(600.0), clip=clip)
            except DriveError as exc:
                u = np.asarray(u)
                ok = np.isfinite(u).all() and ((u >= HAND.u_min) & (u <= HAND.u_max)).all()
                assert (not clip or not np.isfinite(u).all()) and not ok, exc
    assert in_travel(sim, zero)


def test_assign_ids_numbers_the_one_servo_on_the_bus(capsys):
    with SimBus(FAMILY, ids=[FAMILY.factory_id]) as sim:
        code, out, err = run(["drive", "assign-ids", "u3", "--port", sim.port], capsys)
        assert (code, err) == (0, "") and "servo u3: ID 3" in out
        assert [s.servo_id for s in sim.servos] == [3]
        code, out, err = run(["drive", "assign-ids", "u4", "--port", sim.port, "--timeout", "200"], capsys)
        assert code == 2 and err.startswith(f"error: no servo answers at ID {FAMILY.factory_id} on {sim.port}")
        code, out, err = run(["drive", "scan", "--port", sim.port, "--max-id", "6", "--timeout", "200"], capsys)
        assert code == 2 and "ID   3  model 9" in out and err.count("\n") == 1
        assert "servo u1 (ID 1)" in err and "servo u3" not in err


def test_a_servo_without_a_bus_is_refused(tmp_path, capsys):
    from phantom_cad.params import servos

    text = (Path(HAND.params.source).read_text()).replace("[servo]\n", '[servo]\nmodel = "mg90s"\n', 1)
    params = tmp_path / "pwm.toml"
    params.write_text(text)
    code, out, err = run(["drive", "scan", "--port", "/dev/null", "--params", params], capsys)
    assert code == 2 and err.count("\n") == 1 and "[servo] is mg90s, not a bus servo" in err
    assert servos.bus_family("mg90s") is None


def test_drive_imports_no_cad_library():
    code = ("import sys\nfrom phantom_cad import load_params\nfrom phantom_cad.cli import main\n"
            "from phantom_cad.drive.driver import family_of\nfrom phantom_cad.drive.simbus import SimBus\n"
            "with SimBus(family_of(load_params())[1]) as sim:\n"
            "    try:\n"
            "        main(['drive', 'scan', '--port', sim.port, '--max-id', '6', '--timeout', '1000'])\n"
            "    except SystemExit as e:\n"
            "        assert e.code == 0, e.code\n"
            "assert not any(m.split('.')[0] in ('build123d', 'OCP', 'cadquery', 'mujoco') for m in sys.modules)\n")
    env = dict(os.environ, PYTHONPATH=str(Path(__file__).resolve().parents[1]))
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env)
    assert proc.returncode == 0, proc.stderr


def test_moving_needs_the_zero_file(bus, tmp_path, capsys):
    missing = tmp_path / "none.zero.json"
    code, out, err = run(["drive", "move", "--port", bus.port, "--zero", missing, "--", 0, 0, 0, 0, 0, 0], capsys)
    assert code == 2 and err == (f"error: {missing}: no zero file: zero the servos first (phantom-cad drive zero; "
                                 "docs/driving.md)\n")
    assert all(not s.goals for s in bus.servos)


def test_a_reversed_servo_counts_down_as_it_flexes(bus, tmp_path, capsys):
    path = tmp_path / "zero.json"
    code, out, err = run(["drive", "zero", "--port", bus.port, "--zero", path, "--reverse", U3.label], capsys)
    assert (code, err) == (0, "")
    zero = read_zero(path)
    assert [zero.signs[s.index] for s in SERVOS] == [-1 if s is U3 else 1 for s in SERVOS]
    code, out, err = run(["drive", "move", "--port", bus.port, "--zero", path, "--degrees", "--speed", FAST, "--",
                          *[30.0 if s is U3 else 0.0 for s in SERVOS]], capsys)
    assert (code, err) == (0, "")
    assert bus.servo(U3.bus_id).goals[-1] == zero.counts[U3.index] - round(math.radians(30.0) / RES)
    s = bus.servo(U3.bus_id)
    low = P_.unword(s.mem[s.table.min_angle:s.table.min_angle + 2], FAMILY.big_endian)
    assert low == zero.counts[U3.index] - math.floor(HAND.u_max[U3.index] / RES)
    assert in_travel(bus, zero)


def test_merge_interpolates_by_time():
    from phantom_cad.drive.merge import merge_by_time

    class Sweep:
        t = np.array([-0.5, 0.0, 0.5, 1.5, 2.0, 3.0])

        def __len__(self):
            return len(self.t)

    class Angles:
        path = "camera.csv"
        values = {"t": np.array([0.0, 1.0, 2.0]), "q3": np.array([0.0, 1.0, np.nan]),
                  "q15": np.array([2.0, 4.0, 6.0])}

    q, columns = merge_by_time(Sweep(), Angles())
    assert columns == ["q3", "q15"]
    i3, i15 = Q_COLUMNS.index("q3"), Q_COLUMNS.index("q15")
    assert np.array_equal(q[:, i3], [np.nan, 0.0, 0.5, np.nan, np.nan, np.nan], equal_nan=True)
    assert np.array_equal(q[:, i15], [np.nan, 2.0, 3.0, 5.0, 6.0, np.nan], equal_nan=True)
    assert np.isnan(np.delete(q, [i3, i15], axis=1)).all()

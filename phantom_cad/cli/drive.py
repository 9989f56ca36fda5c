"""``phantom-cad drive ...``: the printed hand's servos over their serial bus (phantom_cad.drive;
docs/driving.md). Imports no CAD library. Every failure (no port, a missing servo, a timeout, a
corrupt packet, a servo reporting overload, a command outside the travel) is one ``error:`` line,
exit 2."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

drive_app = typer.Typer(no_args_is_help=True, help="Drive the hand's servos over their serial bus "
                        "(docs/driving.md).")

PortOpt = typer.Option(None, "--port", help="The bus adapter's serial port (/dev/ttyUSB0, COM3).")
BaudOpt = typer.Option(None, "--baud", help="Baud rate (default: the servo family's factory rate).")
ParamsOpt = typer.Option(None, "--params", "-p", help="Parameter file (default: params/phantom.toml).",
                         dir_okay=False)
ZeroOpt = typer.Option(None, "--zero", help="The zero file (default: the parameter file's name with "
                       ".zero.json).", dir_okay=False)
TimeoutOpt = typer.Option(None, "--timeout", help="How long a servo has to answer, ms (default 100).")
SpeedOpt = typer.Option(None, "--speed", help="Ramp speed, deg/s (at most the servo's rated speed).")


def _open(port, baud, params, zero_file=None, need_zero: bool = False, timeout=None):
    """(driver, hand) on the port; the zero file read when ``need_zero``."""
    from .. import load_hand
    from ..drive.bus import TIMEOUT, Bus
    from ..drive.driver import Driver, family_of, read_zero
    from ..drive.protocol import DriveError

    hand = load_hand(params)
    _, family = family_of(hand.params)
    zero = read_zero(zero_path(hand, zero_file)) if need_zero else None
    if port is None:
        raise DriveError("drive: give the bus adapter's serial port with --port (e.g. /dev/ttyUSB0)")
    if timeout is not None and not 0 < timeout < float("inf"):
        raise DriveError(f"--timeout {timeout:g}: must be a positive number of milliseconds")
    bus = Bus(port, baud or family.baud, family.big_endian, TIMEOUT if timeout is None else timeout / 1e3)
    try:
        return Driver(bus, hand, zero), hand
    except BaseException:
        bus.close()
        raise


def zero_path(hand, zero_file) -> Path:
    return Path(zero_file) if zero_file is not None else Path(hand.params.source).with_suffix(".zero.json")


def _speed(driver, speed, default) -> float:
    from ..units import deg

    return driver.speed(min(default, deg(driver.rated_speed)) if speed is None else speed)


def _angles(u) -> str:
    from ..kinematics.topology import SERVOS
    from ..units import deg

    return ", ".join(f"{s.label} {deg(u[s.index]):.2f}" for s in SERVOS) + " deg"


@drive_app.command("scan")
def scan(port: Optional[str] = PortOpt, baud: Optional[int] = BaudOpt,
         timeout: Optional[float] = TimeoutOpt, params: Optional[Path] = ParamsOpt,
         max_id: int = typer.Option(10, "--max-id", help="Ping IDs 0..N (253 for all).", min=0, max=253)):
    """Find the servos on the bus: ID, model number, firmware, and which of the hand's servos each is.
    Exit 2 if one of the six is missing."""
    from ..drive.protocol import DriveError
    from ..kinematics.topology import SERVOS

    driver, _ = _open(port, baud, params, timeout=timeout)
    with driver.bus:
        found = driver.scan(max_id)
    for i, model, fw, count, label in found:
        typer.echo(f"ID {i:3d}  model {model}  firmware {fw[0]}.{fw[1]}  position {count:4d}  "
                   f"{label or '(not one of the hand)'}")
    missing = [s for s in SERVOS if s.bus_id not in {f[0] for f in found}]
    if missing:
        raise DriveError(f"{port}: no answer from " + ", ".join(f"servo {s.label} (ID {s.bus_id})" for s in missing)
                         + ": check its cable and power, or give it its ID (phantom-cad drive assign-ids)")
    typer.echo(f"all {len(SERVOS)} servos answer")


@drive_app.command("assign-ids")
def assign_ids(servo: str = typer.Argument(..., help="The servo to number (u1..u6); connect it alone."),
               from_id: Optional[int] = typer.Option(None, "--from", help="Its present ID (default: the "
                                                     "factory ID).", min=0, max=253),
               port: Optional[str] = PortOpt, baud: Optional[int] = BaudOpt,
         timeout: Optional[float] = TimeoutOpt, params: Optional[Path] = ParamsOpt):
    """Give the one servo on the bus the ID of a servo of the hand (u3 gets ID 3)."""
    driver, _ = _open(port, baud, params, timeout=timeout)
    with driver.bus:
        new = driver.assign_id(servo, driver.family.factory_id if from_id is None else from_id)
    typer.echo(f"servo {servo}: ID {new}")


@drive_app.command("torque")
def torque(state: str = typer.Argument(..., help="on or off"), port: Optional[str] = PortOpt,
           baud: Optional[int] = BaudOpt, timeout: Optional[float] = TimeoutOpt,
           params: Optional[Path] = ParamsOpt, zero_file: Optional[Path] = ZeroOpt):
    """Torque off (limp: the pulleys turn by hand, for tensioning) or on (hold where they are, or at
    the nearest end of the travel, which needs the zero file) on every servo."""
    from ..drive.driver import MOVE_SPEED
    from ..drive.protocol import DriveError

    if state not in ("on", "off"):
        raise DriveError(f"torque: {state!r}: expected on or off")
    driver, _ = _open(port, baud, params, zero_file, need_zero=state == "on", timeout=timeout)
    with driver.bus:
        if state == "on":
            driver.hold(_speed(driver, None, MOVE_SPEED))
        else:
            driver.torque(False)
    typer.echo(f"torque {state} on every servo")


@drive_app.command("zero")
def zero(port: Optional[str] = PortOpt, baud: Optional[int] = BaudOpt,
         timeout: Optional[float] = TimeoutOpt, params: Optional[Path] = ParamsOpt,
         zero_file: Optional[Path] = ZeroOpt,
         reverse: str = typer.Option("", "--reverse", help="Servos whose count falls as the digit flexes "
                                     "(u2,u5): mounted the other way round."),
         torque_limit: float = typer.Option(1.0, "--torque-limit", help="The servos' torque limit, a fraction "
                                            "of the stall torque (written to each servo).")):
    """The tensioning step (docs/assembly.md, docs/driving.md): with torque off, every digit straight and
    its tendon taut, record each servo's position as u = 0, write its travel as its angle limits and the
    torque limit into each servo, and save the zero file."""
    from ..drive.driver import write_zero
    from ..drive.protocol import DriveError
    from ..kinematics.topology import SERVOS

    labels = {s.label: s for s in SERVOS}
    names = [r.strip() for r in reverse.split(",") if r.strip()]
    for n in names:
        if n not in labels:
            raise DriveError(f"--reverse {n!r}: not a servo (servos: {', '.join(labels)})")
    driver, hand = _open(port, baud, params, timeout=timeout)
    with driver.bus:
        z = driver.set_zero(tuple(-1 if s.label in names else 1 for s in SERVOS), torque_limit)
    path = zero_path(hand, zero_file)
    write_zero(path, z)
    typer.echo("zero counts: " + ", ".join(f"{s.label} {z.counts[s.index]}" for s in SERVOS))
    typer.echo(f"wrote {path}; torque is off: phantom-cad drive move or pose turns it on")


@drive_app.command("move")
def move(u: list[float] = typer.Argument(..., help="Six servo angles u1..u6 (radians; --degrees)."),
         degrees: bool = typer.Option(False, "--degrees", help="The angles are degrees."),
         clip: bool = typer.Option(False, "--clip", help="Clip angles outside the travel into it "
                                   "(default: refuse the command)."),
         speed: Optional[float] = SpeedOpt, port: Optional[str] = PortOpt, baud: Optional[int] = BaudOpt,
         timeout: Optional[float] = TimeoutOpt,
         params: Optional[Path] = ParamsOpt, zero_file: Optional[Path] = ZeroOpt):
    """Ramp the six servos to the given angles, checked against the travel in the parameter file."""
    import numpy as np

    from ..drive.driver import MOVE_SPEED
    from ..drive.protocol import DriveError
    from ..units import DEG

    if len(u) != 6:
        raise DriveError(f"move: give six servo angles u1..u6, not {len(u)}")
    target = np.asarray(u, float) * (DEG if degrees else 1.0)
    driver, _ = _open(port, baud, params, zero_file, need_zero=True, timeout=timeout)
    with driver.bus:
        got = driver.move(target, _speed(driver, speed, MOVE_SPEED), clip=clip)
    typer.echo(f"at {_angles(got)}")


@drive_app.command("pose")
def pose(name: str = typer.Argument(..., help="A posture's name (phantom-cad pose --list)."),
         postures: Optional[Path] = typer.Option(None, "--postures", help="A TOML file of more postures.",
                                                 dir_okay=False),
         speed: Optional[float] = SpeedOpt, port: Optional[str] = PortOpt, baud: Optional[int] = BaudOpt,
         timeout: Optional[float] = TimeoutOpt,
         params: Optional[Path] = ParamsOpt, zero_file: Optional[Path] = ZeroOpt):
    """Ramp the servos to a named posture's commands (the control law, as phantom-cad pose prints them);
    a posture the library refuses is not sent."""
    from .. import postures as P
    from ..drive.driver import MOVE_SPEED
    from ..drive.protocol import DriveError

    driver, hand = _open(port, baud, params, zero_file, need_zero=True, timeout=timeout)
    with driver.bus:
        library = P.load(hand, postures)
        if name not in library:
            raise DriveError(f"pose: unknown posture {name!r} (known: {', '.join(library)})")
        result = P.pose(hand, library[name])
        if result.refused:
            raise DriveError(f"pose {name}: refused: the thumb's tip would meet the {result.contact.finger} "
                             "fingertip (phantom-cad pose says where); nothing sent")
        got = driver.move(result.u, _speed(driver, speed, MOVE_SPEED))
    typer.echo(f"posture {name}: at {_angles(got)}")


@drive_app.command("sweep")
def sweep(out: Path = typer.Option(..., "--out", help="The measurement CSV to write.", dir_okay=False),
          speed: Optional[float] = SpeedOpt, port: Optional[str] = PortOpt, baud: Optional[int] = BaudOpt,
         timeout: Optional[float] = TimeoutOpt,
          params: Optional[Path] = ParamsOpt, zero_file: Optional[Path] = ZeroOpt):
    """The calibration sweep: each servo in turn up its travel and back at a set speed, the others at
    rest, recording every servo's own position and the time into the measurement CSV (docs/measurements.md)
    with empty joint-angle columns for a camera's or encoders' angles (phantom-cad drive merge). The file
    is written whole at the end, or not at all."""
    import numpy as np

    from ..calibration.data import write_measurements
    from ..drive.driver import SWEEP_SPEED
    from ..kinematics.topology import N_JOINTS
    from ..units import deg
    from .calibration import CSV_MARKER, check_output

    check_output(out, CSV_MARKER, "a CSV written by phantom-cad")
    driver, hand = _open(port, baud, params, zero_file, need_zero=True, timeout=timeout)
    with driver.bus:
        v = _speed(driver, speed, SWEEP_SPEED)
        t, labels, u = driver.sweep(v)
    write_measurements(out, u, np.full((len(t), N_JOINTS), np.nan), sweep=labels, t=t,
                       comments=[f"phantom-cad drive sweep on {port} at {deg(v):g} deg/s, params digest "
                                 f"{hand.params.digest[:12]}, radians; u: the servos' present positions",
                                 "q: empty, for a camera's or encoders' joint angles (phantom-cad drive merge)"])
    typer.echo(f"wrote {out}: {len(t)} samples, {len(set(labels))} sweeps")


@drive_app.command("merge")
def merge(sweep_csv: Path = typer.Option(..., "--sweep", help="The sweep (phantom-cad drive sweep).",
                                         dir_okay=False),
          angles: Path = typer.Option(..., "--angles", help="Joint angles with a time column t (q1..q15, "
                                      "any subset; radians, or --degrees).", dir_okay=False),
          out: Path = typer.Option(..., "--out", help="The measurement CSV to write.", dir_okay=False),
          degrees: bool = typer.Option(False, "--degrees", help="The angles file is in degrees.")):
    """Fill a sweep's joint angles from a camera's or encoders' file by time: each angle linearly
    interpolated at the sweep's sample times (the two clocks' zero must agree); a sample outside the
    angles' time span stays empty."""
    from ..calibration.data import read_measurements, read_table, write_measurements
    from ..drive.protocol import DriveError
    from ..drive.merge import merge_by_time
    from ..kinematics.topology import Q_COLUMNS
    from .calibration import CSV_MARKER, check_output

    check_output(out, CSV_MARKER, "a CSV written by phantom-cad")
    m = read_measurements(sweep_csv)
    if m.t is None:
        raise DriveError(f"{sweep_csv}: no time column t to merge by")
    table = read_table(angles, required=("t",), optional=Q_COLUMNS, degrees=degrees, allow_empty=Q_COLUMNS)
    q, columns = merge_by_time(m, table)
    write_measurements(out, m.u, q, sweep=[m.sweep_ids[k] for k in m.sweep], t=m.t, q_columns=columns,
                       comments=[f"phantom-cad drive merge --sweep {sweep_csv} --angles {angles}, radians"])
    typer.echo(f"wrote {out}: {len(m)} samples, joint angles {', '.join(columns)}")


@drive_app.command("sim")
def sim(missing: str = typer.Option("", "--missing", help="IDs of servos the simulated bus lacks (3,5).")):
    """A simulated bus of six servos on a pseudo-terminal, to try the commands without a hand: prints its
    port and answers until interrupted (Ctrl-C)."""
    import time

    from .. import load_params
    from ..drive.driver import family_of
    from ..drive.protocol import DriveError
    from ..drive.simbus import Fault, SimBus
    from ..units import deg

    try:
        gone = [int(x) for x in missing.split(",") if x.strip()]
    except ValueError:
        raise DriveError(f"--missing {missing!r}: expected IDs such as 3,5") from None
    p = load_params()
    _, family = family_of(p)
    with SimBus(family, faults=[Fault("missing", i) for i in gone], speed_deg_s=deg(p.servo.speed)) as bus:
        typer.echo(f"simulated bus on {bus.port} (Ctrl-C ends it)")
        while True:
            time.sleep(1.0)

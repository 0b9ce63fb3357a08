"""Joint logs from ROS bags: ``sensor_msgs/JointState`` messages of a ROS 2 bag (SQLite3 or MCAP
storage, a bag folder with ``metadata.yaml`` or one storage file) or a ROS 1 ``.bag``, read with
the ``rosbags`` package (pure Python, no ROS installation needed).

Each message contributes one sample: the time stamp of its header (the recording time when the
header is not stamped), the positions, and the velocities and efforts when the message carries
them. Joints are matched by name to the robot's joints, in the robot's order; other joints in the
messages (a gripper, say) are ignored. Missing velocities and accelerations are derived as for a
CSV log (:func:`mindyn.identification.data.differentiate`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .. import _args
from .data import (
    DataError,
    DataFileNotFoundError,
    JointData,
    check_position_units,
    check_time_units,
    check_velocity_units,
    convert_torque,
    fill_derivatives,
    first_not_increasing,
    given_drive_gain,
    positions_beyond_limits,
    refuse_unused_gain,
    without_derivative_edges,
)
from .torque_units import BAG_TORQUE_REMEDY, check_torque_units

__all__ = ["is_rosbag", "read_rosbag"]

JOINT_STATE = "sensor_msgs/msg/JointState"
_ROS1_JOINT_STATE = "sensor_msgs/JointState"


def is_rosbag(path) -> bool:
    """A ROS 2 bag folder (with ``metadata.yaml``), an ``.mcap`` / ``.db3`` file or a ROS 1
    ``.bag`` file."""
    _args.path(path, "path")
    p = Path(path)
    if p.is_dir():
        return (p / "metadata.yaml").is_file()
    return p.suffix.lower() in (".mcap", ".db3", ".bag")


def _reader_classes():
    try:
        from rosbags.highlevel import AnyReader
        from rosbags.typesys import Stores, get_typestore
    except ImportError:
        raise DataError(
            "reading ROS bags needs the 'rosbags' package: pip install rosbags "
            "(or the project's 'ros' extra)"
        ) from None
    return AnyReader, get_typestore(Stores.LATEST)


def read_rosbag(
    path,
    robot,
    *,
    topic: str | None = None,
    torque_unit: str = "Nm",
    require_torque: bool = True,
    drive_gain=None,
    **derivative_settings,
) -> JointData:
    """Read a joint log from a ROS bag.

    Parameters
    ----------
    path : str or Path
        A ROS 2 bag folder, an ``.mcap`` or ``.db3`` file, or a ROS 1 ``.bag`` file.
    robot : Robot
        Its joint names select and order the columns; its drive table converts ``permille``.
    topic : str, optional
        The ``sensor_msgs/JointState`` topic; needed only when the bag has several.
    torque_unit : {"Nm", "permille", "current"}
        Unit of the ``effort`` fields, as in :func:`mindyn.identification.data.read_csv`.
    require_torque : bool
        False accepts messages without efforts (a trajectory); ``tau`` is then None.
    drive_gain : array (n,), optional
        ``current``: the joint-side gains [N m/A] (or the transmissions' motor torque
        constants), instead of the description's, see
        :func:`mindyn.identification.data.convert_torque`; given with efforts in another unit
        (which it would not convert), a DataError.
    **derivative_settings
        ``filter``, ``cutoff``, ``order``, ``window``, ``polyorder`` of
        :func:`mindyn.identification.data.differentiate`, for velocities / accelerations not in
        the messages.

    Returns
    -------
    JointData
        ``t`` in seconds from the first message, ``q``, ``dq``, ``ddq``, ``tau`` of shape
        (m, n): the messages but those at each end where a derived velocity or acceleration
        is the filter's start-up (:func:`~mindyn.identification.data.without_derivative_edges`).

    Raises
    ------
    DataFileNotFoundError
        ``path`` does not exist.
    DataError
        Not a readable bag, no or several JointState topics (the topics are listed), a joint of
        the robot missing from a message (named, with the message's index), positions,
        velocities or efforts missing or not finite, time stamps not increasing, fewer than 2
        samples (or too few beyond the derivatives' filter edges), or ``rosbags`` not
        installed; the units of a CSV log
        (:func:`~mindyn.identification.data.check_time_units`: a median interval between the
        stamps of 0.5 s or more; positions in degrees or millimetres, velocities that are not
        the positions' derivative; efforts of another unit or sign than the description's
        torques, :func:`~mindyn.identification.torque_units.check_torque_units`). The log has
        ``units_checked`` set.
    """
    from ..robot import Robot

    _args.path(path, "path")
    _args.instance(robot, "robot", Robot)
    _args.optional(_args.text, topic, "topic")
    _args.text(torque_unit, "torque_unit")
    drive_gain = given_drive_gain(drive_gain, robot)
    require_torque = _args.flag(require_torque, "require_torque")
    path = Path(path)
    if not path.exists():
        raise DataFileNotFoundError(f"ROS bag '{path}' does not exist")
    AnyReader, typestore = _reader_classes()
    names = list(robot.joint_names)
    try:
        reader = AnyReader([path], default_typestore=typestore)
        reader.open()
    except Exception as e:  # rosbags raises its own error types per storage format
        raise DataError(f"{path}: not a readable ROS bag ({e})") from None
    try:
        states = [c for c in reader.connections if c.msgtype in (JOINT_STATE, _ROS1_JOINT_STATE)]
        topics = sorted({c.topic for c in states})
        if topic is None:
            if not topics:
                found = ", ".join(sorted({f"{c.topic} ({c.msgtype})" for c in reader.connections}))
                raise DataError(
                    f"{path}: no sensor_msgs/JointState topic (topics: {found or 'none'})"
                )
            if len(topics) > 1:
                raise DataError(
                    f"{path}: several JointState topics ({', '.join(topics)}); choose one with "
                    "topic="
                )
            topic = topics[0]
        elif topic not in topics:
            raise DataError(
                f"{path}: no JointState topic '{topic}' (JointState topics: "
                f"{', '.join(topics) or 'none'})"
            )
        conns = [c for c in states if c.topic == topic]
        t, q, dq, tau = [], [], [], []
        for index, (conn, stamp_ns, raw) in enumerate(reader.messages(connections=conns)):
            msg = reader.deserialize(raw, conn.msgtype)
            where = {name: i for i, name in enumerate(msg.name)}
            missing = [name for name in names if name not in where]
            if missing:
                raise DataError(
                    f"{path}, {topic}, message {index}: no joint(s) {', '.join(missing)} "
                    f"(the message names {', '.join(msg.name) or 'none'})"
                )
            cols = [where[name] for name in names]
            stamp = msg.header.stamp
            sec = getattr(stamp, "sec", None)
            sec = stamp.secs if sec is None else sec
            nsec = getattr(stamp, "nanosec", None)
            nsec = stamp.nsecs if nsec is None else nsec
            t.append(sec + 1e-9 * nsec if (sec or nsec) else 1e-9 * stamp_ns)
            q.append(_field(msg.position, cols, path, topic, index, "position", required=True))
            dq.append(_field(msg.velocity, cols, path, topic, index, "velocity"))
            tau.append(_field(msg.effort, cols, path, topic, index, "effort"))
    finally:
        reader.close()
    if len(t) < 2:
        raise DataError(f"{path}, {topic}: {len(t)} message(s); at least 2 samples are needed")
    t = np.asarray(t)
    k = first_not_increasing(t)
    if k is not None:
        raise DataError(
            f"{path}, {topic}, message {k}: time stamp not increasing (t = {t[k]:.9f} s after "
            f"{t[k - 1]:.9f} s)"
        )
    q = np.asarray(q)
    dq = _complete(dq, path, topic, "velocity")
    tau = _complete(tau, path, topic, "effort")
    if tau is None and require_torque:
        raise DataError(f"{path}, {topic}: the messages carry no efforts (joint torques)")
    check_time_units(
        t,
        f"{path}, {topic}",
        "a JointState stamp is sec + 1e-9 nanosec s: record the stamps in s",
    )
    check_position_units(q, robot, str(path))
    if dq is not None:
        check_velocity_units(t, q, dq, str(path))
    processing: dict = {"samples": len(t), "topic": topic, "joints": names}
    beyond = positions_beyond_limits(q, robot)
    if beyond:
        processing["beyond_limits"] = beyond
    if tau is not None:
        tau, processing["torque"] = convert_torque(tau, torque_unit, robot, drive_gain=drive_gain)
    refuse_unused_gain(
        drive_gain, f"{path}, {topic}", processing.get("torque"), "torque_unit='current'"
    )
    dq, ddq, deriv = fill_derivatives(t - t[0], q, dq, None, **derivative_settings)
    processing.update(deriv)
    if tau is not None:
        check_torque_units(t - t[0], q, dq, tau, robot, str(path), BAG_TORQUE_REMEDY)
    data = JointData(
        t - t[0], q, dq, ddq, tau, source=str(path), processing=processing, units_checked=True
    )
    return without_derivative_edges(data)


def _field(values, cols, path, topic, index, what, required=False):
    """The robot's entries of one array field of a message, or None when the field is empty."""
    values = np.asarray(values, dtype=float)
    if values.size == 0 and not required:
        return None
    if values.size <= max(cols):
        raise DataError(
            f"{path}, {topic}, message {index}: {values.size} {what} value(s) for "
            f"{max(cols) + 1} named joints"
        )
    out = values[cols]
    if not np.all(np.isfinite(out)):
        raise DataError(f"{path}, {topic}, message {index}: {what} is NaN or infinite")
    return out


def _complete(rows, path, topic, what):
    """Stacks a field present in every message; None when absent from all of them."""
    present = [r is not None for r in rows]
    if not any(present):
        return None
    if not all(present):
        k = present.index(False)
        raise DataError(f"{path}, {topic}, message {k}: no {what}, though other messages have it")
    return np.asarray(rows)

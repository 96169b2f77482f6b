#!/usr/bin/env python3
"""Writes a CARMEN log (.clf) as a ROS 2 bag, with the `rosbags` package as the writer.

The bag holds what a ROS 2 robot records:
  /scan        sensor_msgs/msg/LaserScan  (frame_id `laser`, REP 117 ranges)
  /odom        nav_msgs/msg/Odometry      (odom -> base_link, no covariance: zeros)
  /tf          tf2_msgs/msg/TFMessage     (odom -> base_link, the same poses)
  /tf_static   tf2_msgs/msg/TFMessage     (base_link -> laser, --laser-offset metres ahead)

A CARMEN `FLASER` line's odometry is the laser's pose (the logs used here say no laser
offset), so base_link is put --laser-offset metres behind it: the laser, carried back
through the mount on /tf_static, is where the log has it. `ODOM` lines are the robot's
pose and are written as they are. Each message is stamped (header and bag time) with the
line's ipc_timestamp.

Usage: clf_to_rosbag2.py LOG.clf OUT_DIR --storage mcap|sqlite3 [--laser-offset 0.25]
       [--frames N] [--wrong-type-after N]
OUT_DIR must not exist (rosbag2 writers create it). --wrong-type-after N puts a
std_msgs/msg/String on /scan after its N-th scan (a damaged bag, for the tests).
"""

import argparse
import math
import sys
from pathlib import Path

import numpy as np
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore

# The range at or beyond which a CARMEN FLASER reading is a no-return (lidar-replay's
# FLASER_RANGE_MAX): written as +inf, as a REP 117 driver does.
RANGE_MAX = 50.0
# FLASER bearing steps by beam count (SICK LMS modes), degrees.
STEP_DEGREES = {180: 1.0, 181: 1.0, 360: 0.5, 361: 0.5, 721: 0.25}


def stamp_ns(text):
    """CARMEN decimal seconds to integer nanoseconds, exactly."""
    whole, _, fraction = text.partition('.')
    fraction = (fraction + '000000000')[:9]
    return int(whole) * 1_000_000_000 + int(fraction)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('log', type=Path)
    parser.add_argument('out', type=Path)
    parser.add_argument('--storage', choices=['mcap', 'sqlite3'], required=True)
    parser.add_argument('--laser-offset', type=float, default=0.25)
    parser.add_argument('--frames', type=int, default=0, help='scans to write; 0 = all')
    parser.add_argument('--wrong-type-after', type=int, default=0,
                        help='write a std_msgs/msg/String on /scan after this scan')
    args = parser.parse_args()

    store = get_typestore(Stores.ROS2_HUMBLE)
    LaserScan = store.types['sensor_msgs/msg/LaserScan']
    Odometry = store.types['nav_msgs/msg/Odometry']
    TFMessage = store.types['tf2_msgs/msg/TFMessage']
    TransformStamped = store.types['geometry_msgs/msg/TransformStamped']
    Transform = store.types['geometry_msgs/msg/Transform']
    Header = store.types['std_msgs/msg/Header']
    Time = store.types['builtin_interfaces/msg/Time']
    Vector3 = store.types['geometry_msgs/msg/Vector3']
    Quaternion = store.types['geometry_msgs/msg/Quaternion']
    Point = store.types['geometry_msgs/msg/Point']
    Pose = store.types['geometry_msgs/msg/Pose']
    PoseWithCovariance = store.types['geometry_msgs/msg/PoseWithCovariance']
    Twist = store.types['geometry_msgs/msg/Twist']
    TwistWithCovariance = store.types['geometry_msgs/msg/TwistWithCovariance']

    def header(ns, frame):
        return Header(stamp=Time(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000), frame_id=frame)

    def yaw_quaternion(yaw):
        return Quaternion(x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2))

    def transform(ns, parent, child, x, y, yaw):
        return TransformStamped(
            header=header(ns, parent),
            child_frame_id=child,
            transform=Transform(translation=Vector3(x=x, y=y, z=0.0), rotation=yaw_quaternion(yaw)),
        )

    # Odometry poses (base_link in odom) and scans, from the log's lines in file order.
    records = []
    scans = 0
    with open(args.log, encoding='ascii', errors='replace') as log:
        for line in log:
            tokens = line.split()
            if not tokens:
                continue
            if tokens[0] == 'FLASER':
                n = int(tokens[1])
                ranges = [float(r) for r in tokens[2:2 + n]]
                x, y, theta = (float(v) for v in tokens[2 + n + 3:2 + n + 6])
                ns = stamp_ns(tokens[2 + n + 6])
                # The laser's pose is the log's; base_link sits behind it.
                base = (x - args.laser_offset * math.cos(theta),
                        y - args.laser_offset * math.sin(theta), theta)
                records.append(('odom', ns, base))
                records.append(('scan', ns, ranges))
                scans += 1
                if args.frames and scans == args.frames:
                    break
            elif tokens[0] == 'ODOM':
                x, y, theta = (float(v) for v in tokens[1:4])
                records.append(('odom', stamp_ns(tokens[7]), (x, y, theta)))
    if not records:
        sys.exit(f'{args.log}: no FLASER or ODOM line')
    first_ns = min(ns for _, ns, _ in records)

    plugin = StoragePlugin.MCAP if args.storage == 'mcap' else StoragePlugin.SQLITE3
    with Writer(args.out, version=9, storage_plugin=plugin) as writer:
        def connection(topic, msgtype):
            return writer.add_connection(topic, msgtype, typestore=store)

        tf_static = connection('/tf_static', TFMessage.__msgtype__)
        scan_topic = connection('/scan', LaserScan.__msgtype__)
        odom_topic = connection('/odom', Odometry.__msgtype__)
        tf_topic = connection('/tf', TFMessage.__msgtype__)
        String = store.types['std_msgs/msg/String']
        wrong = connection('/scan', String.__msgtype__) if args.wrong_type_after else None
        written = 0

        def write(conn, ns, message):
            writer.write(conn, ns, store.serialize_cdr(message, conn.msgtype))

        mount = transform(first_ns, 'base_link', 'laser', args.laser_offset, 0.0, 0.0)
        write(tf_static, first_ns, TFMessage(transforms=[mount]))
        zeros = np.zeros(36, dtype=np.float64)
        for kind, ns, value in records:
            if kind == 'scan':
                n = len(value)
                step = math.radians(STEP_DEGREES.get(n, 1.0))
                ranges = np.array(
                    [math.nan if r <= 0 else math.inf if r >= RANGE_MAX else r for r in value],
                    dtype=np.float32,
                )
                write(scan_topic, ns, LaserScan(
                    header=header(ns, 'laser'),
                    angle_min=-math.pi / 2,
                    angle_max=-math.pi / 2 + (n - 1) * step,
                    angle_increment=step,
                    time_increment=0.0,
                    scan_time=0.0,
                    range_min=0.0,
                    range_max=RANGE_MAX,
                    ranges=ranges,
                    intensities=np.array([], dtype=np.float32),
                ))
                written += 1
                if wrong is not None and written == args.wrong_type_after:
                    write(wrong, ns + 1, String(data='not a scan'))
            else:
                x, y, yaw = value
                write(odom_topic, ns, Odometry(
                    header=header(ns, 'odom'),
                    child_frame_id='base_link',
                    pose=PoseWithCovariance(
                        pose=Pose(position=Point(x=x, y=y, z=0.0), orientation=yaw_quaternion(yaw)),
                        covariance=zeros,
                    ),
                    twist=TwistWithCovariance(
                        twist=Twist(linear=Vector3(x=0.0, y=0.0, z=0.0), angular=Vector3(x=0.0, y=0.0, z=0.0)),
                        covariance=zeros,
                    ),
                ))
                write(tf_topic, ns, TFMessage(transforms=[transform(ns, 'odom', 'base_link', x, y, yaw)]))
    print(f'{args.out}: {scans} scans, {sum(1 for r in records if r[0] == "odom")} odometry poses')


if __name__ == '__main__':
    main()

#!/usr/bin/env python3
"""Writes the ROS bags test_rosbag reads, with the bag writer of Debian's python3-rosbag and the
message classes of python3-sensor-msgs (an implementation independent of imu-sim's reader):

    /usr/bin/python3 tests/host_sim/make_rosbags.py OUTDIR

OUTDIR/plain.bag  uncompressed chunks, /imu (sensor_msgs/Imu) and /status (std_msgs/String)
OUTDIR/lz4.bag    the same messages in LZ4 chunks of about 8 KiB (many chunks)
OUTDIR/bz2.bag    the same messages in BZ2 chunks
OUTDIR/two.bag    /imu0 and /imu1 (sensor_msgs/Imu), /status
OUTDIR/zero.bag   /imu with every header stamp zero (the record times carry the clock)
OUTDIR/imu.csv    /imu's samples: t_ns (the header stamps), acc_x .. gyro_z
OUTDIR/imu1.csv   /imu1's samples of two.bag

The samples: 3000 at 200 Hz from the epoch 1.7e9 s (5 ms steps in exact nanoseconds), a
deterministic pseudo-random sequence (a 32-bit LCG), with the 10 samples 1500..1509 not
written (a gap of 10 samples).
"""
import sys

import genpy
import rosbag
from sensor_msgs.msg import Imu
from std_msgs.msg import String

N = 3000
STEP_NS = 5000000
EPOCH_NS = 1700000000 * 1000000000 + 123
GAP = range(1500, 1510)
NAMES = ["acc_x", "acc_y", "acc_z", "gyro_x", "gyro_y", "gyro_z"]


def samples(seed):
    """N rows of (t_ns, acc_x, acc_y, acc_z, gyro_x, gyro_y, gyro_z), the gap left out."""
    s = seed
    rows = []
    for i in range(N):
        vals = []
        for c in range(6):
            s = (s * 1103515245 + 12345) % 2**32
            u = ((s >> 8) % 20001 - 10000) * 1e-6
            vals.append((9.81 if c == 2 else 0.0) + (u * 0.05 if c < 3 else u * 0.01))
        if i not in GAP:
            rows.append((EPOCH_NS + i * STEP_NS, vals))
    return rows


def imu_msg(t_ns, vals, seq, frame):
    m = Imu()
    m.header.seq = seq
    m.header.stamp = genpy.Time(t_ns // 1000000000, t_ns % 1000000000)
    m.header.frame_id = frame
    m.orientation.w = 1.0
    m.linear_acceleration.x, m.linear_acceleration.y, m.linear_acceleration.z = vals[0:3]
    m.angular_velocity.x, m.angular_velocity.y, m.angular_velocity.z = vals[3:6]
    m.orientation_covariance[0] = -1.0
    return m


def write_csv(path, rows):
    with open(path, "w") as f:
        f.write("t_ns," + ",".join(NAMES) + "\n")
        for t_ns, vals in rows:
            f.write(str(t_ns) + "," + ",".join(repr(v) for v in vals) + "\n")


def write_bag(path, topics, compression="none", chunk_threshold=16 * 1024, zero_stamps=False):
    """topics: {name: rows}; every message recorded 1 ms after its stamp."""
    with rosbag.Bag(path, "w", compression=compression, chunk_threshold=chunk_threshold) as bag:
        events = []
        for k, (topic, rows) in enumerate(sorted(topics.items())):
            for seq, (t_ns, vals) in enumerate(rows):
                events.append((t_ns + 1000000 + k, topic, seq, t_ns, vals))
        events.sort()
        for n, (rec_ns, topic, seq, t_ns, vals) in enumerate(events):
            msg = imu_msg(0 if zero_stamps else t_ns, vals, seq, "imu_link")
            rec = genpy.Time(rec_ns // 1000000000, rec_ns % 1000000000)
            bag.write(topic, msg, t=rec)
            if n % 500 == 0:
                bag.write("/status", String(data="ok %d" % n), t=rec)


def main():
    out = sys.argv[1]
    imu = samples(12345)
    imu1 = samples(777)
    write_csv(out + "/imu.csv", imu)
    write_csv(out + "/imu1.csv", imu1)
    write_bag(out + "/plain.bag", {"/imu": imu})
    write_bag(out + "/lz4.bag", {"/imu": imu}, compression="lz4", chunk_threshold=8 * 1024)
    write_bag(out + "/bz2.bag", {"/imu": imu}, compression="bz2")
    write_bag(out + "/two.bag", {"/imu0": imu, "/imu1": imu1})
    # Record times on the grid too: they are the clock when the stamps are all zero.
    write_bag(out + "/zero.bag", {"/imu": imu}, zero_stamps=True)


if __name__ == "__main__":
    main()

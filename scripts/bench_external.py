#!/usr/bin/python3
"""External baselines for scripts/bench.py: robot_localization's EKF fed the IMU alone, and
imu_tools' Madgwick attitude feeding our compensator's gravity removal. Their code is not in this
repository: give the devel (or install) folders of built copies; without them this prints why
nothing was measured and exits 0.

  scripts/bench_external.py accuracy --bin BIN --scenarios A.yaml B.yaml --seeds N --work DIR
                                     [--robot-localization DEVEL] [--imu-tools DEVEL]
  scripts/bench_external.py throughput --bag BAG --robot-localization DEVEL [--seconds S]

accuracy: per scenario and seed, simulate_imu writes the bag; this script publishes its IMU
messages, stamps kept, into ekf_localization_node (config/bench/ekf_imu_only.yaml) and
imu_filter_node (config/bench/madgwick.yaml) at once, with at most 4 of Madgwick's answers
outstanding (its input queue holds 5: none is lost) and each message sent after the EKF's output
of the previous one (deterministic runs), and keeps their outputs. The nodes run on the
wall clock (no /clock): both work from the header stamps, and robot_localization on simulated time
divides by a zero time step when its timer catches up (NaN accelerations, dropped at random).
Madgwick's attitude (yaw aligned once with the bag's first orientation: it has no magnetometer)
replaces the bag's orientation and compensate_bag (default mode) runs over it.
evaluate_compensator --estimate scores both against the scenario's truth with the metrics of the
other methods and prints the table (markdown) on stdout.
throughput: robot_localization's node fed BAG's IMU messages back to back (queue large enough
for all): the wall time until its output reaches the bag's end (bounded by this
Python player, slower than the node) and the node's own CPU time, whose messages per CPU second
is its fastest rate on one core. Prints a markdown table (header and one row).
"""
import argparse
import math
import os
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
import warnings

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
EKF_CONFIG = os.path.join(REPO, 'config/bench/ekf_imu_only.yaml')
MADGWICK_CONFIG = os.path.join(REPO, 'config/bench/madgwick.yaml')
EKF_NODE = 'lib/robot_localization/ekf_localization_node'
MADGWICK_NODE = 'lib/imu_filter_madgwick/imu_filter_node'
MADGWICK_WINDOW = 4  # messages sent ahead of Madgwick's answers; its input queue holds 5
# Not in Debian: built beside them from their sources (their commits are printed).
BUILD_DEPENDENCIES = ('geographic_msgs', 'uuid_msgs', 'eigen_conversions', 'cmake_modules', 'roslint')


def log(*args):
    print('[bench_external]', *args, file=sys.stderr, flush=True)


def built(devel, node, what):
    """The node's path, or None with the reason on stderr."""
    if not devel:
        log('%s: no built copy given, skipped' % what)
        return None
    path = os.path.join(devel, node)
    if not os.access(path, os.X_OK):
        log('%s: %s not found, skipped' % (what, path))
        return None
    return path


def sourced_env(devels, ros_home, port):
    """The environment of each DEVEL/setup.bash, on a private master."""
    source = ' && '.join('source "%s/setup.bash" --extend' % d for d in dict.fromkeys(devels))
    out = subprocess.run(['bash', '-c', source + ' && env -0'], check=True,
                         stdout=subprocess.PIPE).stdout.decode()
    env = dict(kv.split('=', 1) for kv in out.split('\0') if '=' in kv)
    env.update(ROS_MASTER_URI='http://127.0.0.1:%d' % port, ROS_HOME=ros_home, ROS_LOG_DIR=ros_home,
               PATH='/usr/sbin:/usr/bin:/sbin:/bin')
    return env


class Ros:
    """A private roscore and the processes started on it."""

    def __init__(self, devels, work):
        with socket.socket() as s:
            s.bind(('127.0.0.1', 0))
            self.port = s.getsockname()[1]
        self.env = sourced_env(devels, os.path.join(work, 'ros_home'), self.port)
        self.procs = []
        self.core = self.start(['roscore', '-p', str(self.port)])
        deadline = time.time() + 30
        while subprocess.run(['rosparam', 'set', '/use_sim_time', 'false'], env=self.env,
                             stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL).returncode:
            if time.time() > deadline:
                raise RuntimeError('roscore did not start')
            time.sleep(0.5)
        os.environ.update(self.env)
        import rospy
        rospy.init_node('bench_external', disable_signals=True)

    def start(self, cmd):
        p = subprocess.Popen(cmd, env=self.env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                             start_new_session=True)
        self.procs.append(p)
        return p

    def run(self, cmd):
        subprocess.run(cmd, env=self.env, check=True, stdout=subprocess.DEVNULL)

    def node(self, path, name, config, remaps=()):
        self.run(['rosparam', 'load', config, '/' + name])
        return self.start([path, '__name:=' + name] + list(remaps))

    @staticmethod
    def stop(p):
        if p.poll() is None:
            os.killpg(p.pid, signal.SIGINT)
            try:
                p.wait(20)
            except subprocess.TimeoutExpired:
                os.killpg(p.pid, signal.SIGKILL)
                p.wait()

    def close(self):
        for p in reversed(self.procs):
            self.stop(p)


def imu_topic(bag):
    import rosbag
    with rosbag.Bag(bag) as b:
        topics = [t for t in b.get_type_and_topic_info().topics if t.lstrip('/') == 'imu/data']
        if not topics:
            raise RuntimeError('%s has no imu/data' % bag)
        return topics[0], b.get_message_count(topics[0]), b.get_start_time(), b.get_end_time()


class Collector:
    """Messages of one topic, kept in arrival order."""

    def __init__(self, topic, msg_type, queue_size):
        import rospy
        self.msgs = []
        self.cond = threading.Condition()
        self.sub = rospy.Subscriber(topic, msg_type, self.add, queue_size=queue_size, tcp_nodelay=True)

    def add(self, msg):
        with self.cond:
            self.msgs.append(msg)
            self.cond.notify_all()

    def wait(self, done, timeout, what):
        with self.cond:
            if not self.cond.wait_for(lambda: done(self.msgs), timeout):
                raise RuntimeError('%s: no answer after %g s' % (what, timeout))


def replay(ros, bag, ekf, madgwick, seconds=None, lockstep=True):
    """Publishes BAG's IMU messages (stamps kept) into the nodes started here.
    With LOCKSTEP each message waits for the EKF's output of the previous one (it fuses each
    message alone, so equal-stamp parts are always fused in the same order: its IMU-only state
    amplifies any difference, and runs would differ); with Madgwick at most MADGWICK_WINDOW
    messages are unanswered at any time; otherwise they are sent back to back (the EKF's queue holds them all). Returns the EKF's odometry, Madgwick's
    IMU messages, the wall time until the EKF's output reached the end, and the EKF's CPU time."""
    import rosbag
    import rospy
    from nav_msgs.msg import Odometry
    from sensor_msgs.msg import Imu
    topic, count, start, end = imu_topic(bag)
    end = min(end, start + seconds) if seconds else end
    nodes, odom, att = [], None, None
    if ekf:
        nodes.append(ros.node(ekf, 'ekf', EKF_CONFIG))
        odom = Collector('/odometry/filtered', Odometry, 100000)
    if madgwick:
        nodes.append(ros.node(madgwick, 'madgwick', MADGWICK_CONFIG,
                              ['imu/data_raw:=/imu/data', 'imu/data:=/madgwick/imu']))
        att = Collector('/madgwick/imu', Imu, 100000)
    warnings.filterwarnings('ignore', 'The publisher should be created')  # queue_size=None: synchronous
    imu = rospy.Publisher('/imu/data', Imu, queue_size=None, tcp_nodelay=True)
    connected = [(imu, len(nodes))] + [(c.sub, 1) for c in (odom, att) if c]
    deadline = time.time() + 30
    while not all(x.get_num_connections() >= n for x, n in connected):
        if time.time() > deadline or any(n.poll() is not None for n in nodes):
            raise RuntimeError('the nodes did not connect within 30 s')
        time.sleep(0.1)
    t0 = time.time()
    sent = 0
    with rosbag.Bag(bag) as b:
        for _, m, _ in b.read_messages(topics=[topic]):
            if m.header.stamp.to_sec() > end:
                break
            imu.publish(m)
            sent += 1
            if odom and lockstep:
                stamp = m.header.stamp
                odom.wait(lambda msgs: msgs and msgs[-1].header.stamp >= stamp, 10.0, 'EKF, message %d' % sent)
            if att:  # at most MADGWICK_WINDOW unanswered: its queue (5) never overflows
                att.wait(lambda msgs: len(msgs) >= sent - MADGWICK_WINDOW, 10.0, 'Madgwick, message %d' % sent)
    if att:
        att.wait(lambda msgs: len(msgs) >= sent, 10.0, 'Madgwick, last messages')
    if odom:
        odom.wait(lambda msgs: msgs and msgs[-1].header.stamp.to_sec() >= end, 60.0, 'EKF, end of ' + bag)
    wall = time.time() - t0
    cpu = cpu_seconds(nodes[0].pid) if ekf else float('nan')
    for n in nodes:
        Ros.stop(n)
    for c in (odom, att):
        if c:
            c.sub.unregister()
    return (odom.msgs if odom else None), (att.msgs if att else None), wall, cpu, sent


def cpu_seconds(pid):
    with open('/proc/%d/stat' % pid) as f:
        fields = f.read().rsplit(')', 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf('SC_CLK_TCK')


def quat_mul(a, b):
    aw, ax, ay, az = a
    bw, bx, by, bz = b
    return (aw * bw - ax * bx - ay * by - az * bz, aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx, aw * bz + ax * by - ay * bx + az * bw)


def yaw(q):
    w, x, y, z = q
    return math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))


def write_madgwick_input(bag, att, out):
    """BAG's IMU messages with Madgwick's orientation, its yaw turned once onto the bag's first
    orientation's (Madgwick has no magnetometer here, so its heading starts arbitrary)."""
    import rosbag
    topic, _, _, _ = imu_topic(bag)
    by_stamp = {m.header.stamp: m.orientation for m in att}
    turn = None
    with rosbag.Bag(bag) as b, rosbag.Bag(out, 'w') as w:
        for _, m, t in b.read_messages(topics=[topic]):
            q = by_stamp[m.header.stamp]
            q = (q.w, q.x, q.y, q.z)
            if turn is None:
                o = m.orientation
                d = yaw((o.w, o.x, o.y, o.z)) - yaw(q)
                turn = (math.cos(d / 2), 0.0, 0.0, math.sin(d / 2))
            m.orientation.w, m.orientation.x, m.orientation.y, m.orientation.z = quat_mul(turn, q)
            w.write(topic, m, t)


def write_odometry(msgs, out):
    import rosbag
    with rosbag.Bag(out, 'w') as w:
        for m in msgs:
            w.write('odometry/filtered', m, m.header.stamp)


def commit_of(devel, package):
    """The short commit of PACKAGE's sources beside DEVEL (a catkin workspace's src/), if known: from
    their git checkout, else from the line "PACKAGE COMMIT" of COMMITS.txt in the workspace (sources
    copied without their history); "unknown" otherwise."""
    workspace = os.path.dirname(os.path.abspath(devel))
    for root, dirs, files in os.walk(os.path.join(workspace, 'src')):
        if 'package.xml' in files and '<name>%s</name>' % package in open(os.path.join(root, 'package.xml')).read():
            r = subprocess.run(['git', '-C', root, 'log', '-1', '--format=%h (%cd)', '--date=short'],
                               stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
            if r.returncode == 0 and r.stdout.strip():
                return r.stdout.strip()
            break
        dirs[:] = [d for d in dirs if not d.startswith('.')]
    listed = os.path.join(workspace, 'COMMITS.txt')
    if os.path.exists(listed):
        with open(listed) as f:
            for line in f:
                fields = line.split()
                if len(fields) >= 2 and fields[0] == package:
                    return fields[1][:7]
    return 'unknown'


def accuracy(args):
    ekf = built(args.robot_localization, EKF_NODE, "robot_localization's ekf_localization_node")
    madgwick = built(args.imu_tools, MADGWICK_NODE, "imu_tools' imu_filter_node")
    if not ekf and not madgwick:
        print('robot_localization and imu_tools were not measured in this run: no built copy was given '
              '(`scripts/bench.py run --robot-localization DEVEL --imu-tools DEVEL`).')
        return
    for path, devel, package in ((ekf, args.robot_localization, 'robot_localization'),
                                 (madgwick, args.imu_tools, 'imu_filter_madgwick')):
        # The node inside the given devel folder: no machine's own path in the published tables.
        print('- %s: %s' % (package, 'DEVEL/%s, commit %s' % (os.path.relpath(path, devel), commit_of(devel, package))
                            if path else
                            'not measured (no built copy given)'))
    devel = args.robot_localization if ekf else args.imu_tools
    print('- built in the same workspace from: %s' % ', '.join(
        '%s %s' % (p, commit_of(devel, p).split()[0]) for p in BUILD_DEPENDENCIES))
    print('- seeds 1..%d\n' % args.seeds, flush=True)
    os.makedirs(args.work, exist_ok=True)
    ros = Ros([d for d, node in ((args.robot_localization, ekf), (args.imu_tools, madgwick)) if node], args.work)
    try:
        for scenario in args.scenarios:
            name = os.path.splitext(os.path.basename(scenario))[0]
            estimates = []
            for seed in range(1, args.seeds + 1):
                log('%s seed %d' % (name, seed))
                bag = os.path.join(args.work, '%s_%d.bag' % (name, seed))
                subprocess.run([os.path.join(args.bin, 'simulate_imu'), '--scenario', scenario, '--seed',
                                str(seed), '--out', bag], check=True, stdout=subprocess.DEVNULL)
                odom, att, wall, _, sent = replay(ros, bag, ekf, madgwick)
                log('  %d messages replayed in %.0f s' % (sent, wall))
                stem = os.path.join(args.work, '%s_%d' % (name, seed))
                if ekf:
                    write_odometry(odom, stem + '_ekf.bag')
                if madgwick:
                    write_madgwick_input(bag, att, stem + '_madgwick_in.bag')
                    subprocess.run([os.path.join(args.bin, 'compensate_bag'), '--in', stem + '_madgwick_in.bag',
                                    '--out', stem + '_madgwick_out.bag'], check=True, stdout=subprocess.DEVNULL,
                                   stderr=subprocess.DEVNULL)
                    os.remove(stem + '_madgwick_in.bag')
                os.remove(bag)
            if ekf:
                estimates += ['--estimate', 'robot_localization EKF=' +
                              os.path.join(args.work, '%s_{seed}_ekf.bag' % name)]
            if madgwick:
                estimates += ['--estimate', 'Madgwick + default=' +
                              os.path.join(args.work, '%s_{seed}_madgwick_out.bag' % name)]
            print('### %s\n' % name, flush=True)
            subprocess.run([os.path.join(args.bin, 'evaluate_compensator'), '--scenario', scenario, '--seeds',
                            str(args.seeds)] + estimates, check=True)
            print(flush=True)
            for f in os.listdir(args.work):
                if f.startswith(name + '_') and f.endswith('.bag'):
                    os.remove(os.path.join(args.work, f))
    finally:
        ros.close()


# --- Real recordings (../shared/data): each set as a bag, scored against its own reference ---
G = 9.80665
D2R = math.pi / 180
STAMP0 = 1000.0  # stamps start here, not at 0: a zero stamp means "no time" to ROS nodes


def csv_columns(path, skip=0):
    import numpy as np
    return np.genfromtxt(path, delimiter=',', skip_header=skip + 1)


def rotation_to_quat(r):
    """wxyz quaternions of rotation matrices (n x 3 x 3)."""
    import numpy as np
    w = np.sqrt(np.maximum(0.0, 1 + r[:, 0, 0] + r[:, 1, 1] + r[:, 2, 2])) / 2
    x = np.copysign(np.sqrt(np.maximum(0.0, 1 + r[:, 0, 0] - r[:, 1, 1] - r[:, 2, 2])) / 2, r[:, 2, 1] - r[:, 1, 2])
    y = np.copysign(np.sqrt(np.maximum(0.0, 1 - r[:, 0, 0] + r[:, 1, 1] - r[:, 2, 2])) / 2, r[:, 0, 2] - r[:, 2, 0])
    z = np.copysign(np.sqrt(np.maximum(0.0, 1 - r[:, 0, 0] - r[:, 1, 1] + r[:, 2, 2])) / 2, r[:, 1, 0] - r[:, 0, 1])
    return np.stack([w, x, y, z], -1)


def xio_oscillatory(data):
    """x-IMU, 256 Hz; its onboard AHRS quaternion (x-io's convention: earth relative to sensor,
    conjugated here). Reference: at rest at the same place at the start and at the end."""
    import numpy as np
    d = csv_columns(os.path.join(data, 'xio_oscillatory/LoggedData_CalInertialAndMag.csv'))
    q = csv_columns(os.path.join(data, 'xio_oscillatory/LoggedData_Quaternion.csv'))
    k = np.clip(np.searchsorted(q[:, 0], d[:, 0], side='right') - 1, 0, len(q) - 1)
    quat = q[k, 1:5] * np.array([1, -1, -1, -1])
    return np.arange(len(d)) / 256.0, d[:, 4:7] * G, d[:, 1:4] * D2R, quat, 6.0


def ngimu_heave(data):
    """NGIMU: only its earth-frame, gravity-free acceleration was logged (no gyro): specific force
    = that + g, identity attitude, zero rate. Reference: ~0.30 m raise and return (README)."""
    import numpy as np
    d = csv_columns(os.path.join(data, 'xio_ngimu_heave_30cm/earth.csv'))
    accel = (d[:, 1:4] + np.array([0, 0, 1.0])) * G
    quat = np.tile([1.0, 0, 0, 0], (len(d), 1))
    return d[:, 0], accel, np.zeros_like(accel), quat, 4.0


def buoy_morro_bay(data):
    """MicroStrain 3DM-GX3 in a moored buoy, 10 Hz, its own AHRS (NED, z down: turned 180 deg about
    x into a z-up body frame, ENU world). Reference: moored, its mean position does not move."""
    import numpy as np
    d = csv_columns(os.path.join(data, 'buoy_morro_bay/morro_bay_z06_20201201_imu.csv'))
    flip = np.array([1.0, -1.0, -1.0])
    roll, pitch, yaw_ = d[:, 9], d[:, 10], d[:, 11]
    cr, sr, cp, sp, cy, sy = np.cos(roll), np.sin(roll), np.cos(pitch), np.sin(pitch), np.cos(yaw_), np.sin(yaw_)
    r_ned_frd = np.stack([np.stack([cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr], -1),
                          np.stack([sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr], -1),
                          np.stack([-sp, cp * sr, cp * cr], -1)], -2)
    enu_ned = np.array([[0, 1.0, 0], [1.0, 0, 0], [0, 0, -1.0]])
    r = enu_ned @ r_ned_frd @ np.diag(flip)
    return d[:, 1] - d[0, 1], d[:, 3:6] * G * flip, d[:, 6:9] * flip, rotation_to_quat(r), None


def robot_arm(data):
    """MPU-9150 on an ABB robot (axes = the robot's at the start), ~101 Hz of PC receive stamps;
    attitude from the robot's own orientation quaternion, conjugated (the convention that levels
    gravity: mean (0, 0, 1.02) g, std 0.05 g; unconjugated std 0.9 g). Reference: the robot's tool
    position."""
    import numpy as np
    d = csv_columns(os.path.join(data, 'robot_arm_ground_truth/eV50p_Sequencia2_MPU9150.csv'))
    return d[:, 0] - d[0, 0], d[:, 1:4] * G, d[:, 4:7] * D2R, d[:, 13:17] * np.array([1, -1, -1, -1]), 1.0


def write_imu_bag(path, t, accel, gyro, quat, orientation=True):
    """The recording as imu/data; orientation=False marks every orientation unknown (REP-145:
    orientation_covariance[0] = -1), as an IMU without an AHRS reports it."""
    import rosbag
    import rospy
    from sensor_msgs.msg import Imu
    with rosbag.Bag(path, 'w') as b:
        for k in range(len(t)):
            m = Imu()
            m.header.stamp = rospy.Time.from_sec(STAMP0 + t[k])
            m.header.seq = k
            m.header.frame_id = 'imu_link'
            m.orientation.w, m.orientation.x, m.orientation.y, m.orientation.z = quat[k] / math.sqrt(sum(quat[k] ** 2))
            m.angular_velocity.x, m.angular_velocity.y, m.angular_velocity.z = gyro[k]
            m.linear_acceleration.x, m.linear_acceleration.y, m.linear_acceleration.z = accel[k]
            m.orientation_covariance[0::4] = [1e-4] * 3 if orientation else [-1.0, 0.0, 0.0]
            m.angular_velocity_covariance[0::4] = [1e-4] * 3
            m.linear_acceleration_covariance[0::4] = [1e-2] * 3
            w = m.header.stamp
            b.write('imu/data', m, w)


def odometry_positions(bag):
    """{'odometry/filtered' | 'odometry/wave': array of (time, x, y, z)} of an estimator's bag."""
    import numpy as np
    import rosbag
    series = {}
    with rosbag.Bag(bag) as b:
        for topic, m, _ in b.read_messages():
            if topic.lstrip('/') in ('odometry/filtered', 'odometry/wave'):
                p = m.pose.pose.position
                series.setdefault(topic.lstrip('/'), []).append((m.header.stamp.to_sec() - STAMP0, p.x, p.y, p.z))
    return {topic: np.array(rows) for topic, rows in series.items()}


def wave_variances(bag):
    """Array of (time, var x, var y, var z) of the position covariance of an estimator's
    odometry/wave (None without that topic)."""
    import numpy as np
    import rosbag
    rows = []
    with rosbag.Bag(bag) as b:
        for topic, m, _ in b.read_messages():
            if topic.lstrip('/') == 'odometry/wave':
                c = m.pose.covariance
                rows.append((m.header.stamp.to_sec() - STAMP0, c[0], c[7], c[14]))
    return np.array(rows) if rows else None


def position_track(bag):
    """Times and positions (slow + wave motion; slow motion) of an estimator's bag, as published
    (each estimator starts at zero)."""
    import numpy as np
    series = odometry_positions(bag)
    slow = series['odometry/filtered']
    p = slow[:, 1:].copy()
    if 'odometry/wave' in series:
        wave = series['odometry/wave']
        p = p + np.stack([np.interp(slow[:, 0], wave[:, 0], wave[:, i]) for i in (1, 2, 3)], -1)
    return slow[:, 0], p, slow[:, 1:]


def real_errors(name, data, t, total, slow):
    """Error against the set's reference: (number, what it is)."""
    import numpy as np
    if name == 'xio_oscillatory':
        return np.linalg.norm(total[-1]), 'distance from the start position at the end (at rest there) [m]'
    if name == 'xio_ngimu_heave_30cm':
        ref = [(0.5, 4.0, 0.0), (7.0, 10.0, 0.30), (17.0, 20.0, 0.30), (23.5, 27.0, 0.0)]
        e = np.concatenate([total[(t >= a) & (t <= b), 2] - h for a, b, h in ref])
        return math.sqrt(np.mean(e ** 2)), 'RMS height error in the still phases (0, 0.30, 0.30, 0 m) [m]'
    if name == 'buoy_morro_bay':
        return np.linalg.norm(slow[-1]), 'distance of the slow-motion position from the start after 30 min [m]'
    ref = csv_columns(os.path.join(data, 'robot_arm_ground_truth/eV50p_Sequencia2_MPU9150.csv'))
    ref_t = ref[:, 0] - ref[0, 0]
    ref_p = (ref[:, 10:13] - ref[0, 10:13]) / 1000.0
    e = total - np.stack([np.interp(t, ref_t, ref_p[:, i]) for i in range(3)], -1)
    return math.sqrt(np.mean(np.sum(e ** 2, 1))), 'RMS distance from the robot tool position [m]'


def quat_rotate(quat, v):
    """v (n x 3) turned by the wxyz quaternions quat (n x 4), each normalised."""
    import numpy as np
    q = quat / np.linalg.norm(quat, axis=1, keepdims=True)
    w, u = q[:, :1], q[:, 1:]
    return v + 2 * np.cross(u, np.cross(u, v) + w * v)


def spectral_displacement(t, accel, quat, band):
    """The wave displacement of a recording in the frequency domain, independently of the core:
    the specific force turned into the level frame by the recording's own attitude, gravity taken
    off, resampled to its median rate, tapered (Tukey, 10 %), divided by -(2 pi f)^2 inside BAND
    (f_low, f_high) with raised-cosine edges over 30 % of each corner frequency, zero outside.
    Returns the uniform times and the displacement (n x 3)."""
    import numpy as np
    world = quat_rotate(quat, accel) - np.array([0, 0, G])
    dt = float(np.median(np.diff(t)))
    grid = np.arange(t[0], t[-1], dt)
    a = np.stack([np.interp(grid, t, world[:, i]) for i in range(3)], -1)
    a -= a.mean(0)
    n = len(grid)
    k = np.arange(n)
    edge = max(1, int(0.05 * n))
    taper = np.ones(n)
    taper[:edge] = 0.5 - 0.5 * np.cos(np.pi * k[:edge] / edge)
    taper[-edge:] = taper[:edge][::-1]
    spectrum = np.fft.rfft(a * taper[:, None], axis=0)
    f = np.fft.rfftfreq(n, dt)
    low, high = band
    inside = (f > 0.7 * low) & (f < 1.3 * high)
    rising = 0.5 - 0.5 * np.cos(np.pi * (f - 0.7 * low) / (0.6 * low))
    falling = 0.5 + 0.5 * np.cos(np.pi * (f - 0.7 * high) / (0.6 * high))
    w = np.where(f < 1.3 * low, rising, np.where(f > 0.7 * high, falling, 1.0))
    gain = np.zeros_like(f)
    gain[inside] = -w[inside] / (2 * np.pi * f[inside]) ** 2
    return grid, np.fft.irfft(spectrum * gain[:, None], n=n, axis=0)


# Recordings with a wave-like motion compared with spectral_displacement: the band, and the part
# of the recording compared (after the estimators' start, clear of the taper) [s].
SPECTRAL_SETS = {'buoy_morro_bay': ((0.04, 0.5), 300.0, 60.0),
                 'xio_ngimu_heave_30cm': ((0.3, 10.0), 5.0, 3.0)}


# Outputs held at zero during the calibration window carry this variance (1e6) or more: they are
# left out of the published standard deviation.
HELD_VARIANCE = 1e5


def spectral_rows(name, reference, track, variances):
    """Per axis: correlation of the estimator's wave position with the frequency-domain estimate,
    4 x std of each, the RMS of their difference and the standard deviation the estimator
    publishes (root of its mean position variance; NaN without), over the compared part."""
    import numpy as np
    _, start, end_margin = SPECTRAL_SETS[name]
    grid, displacement = reference
    keep = (grid >= grid[0] + start) & (grid <= grid[-1] - end_margin)
    rows = []
    for i, axis in enumerate('xyz'):
        ours = np.interp(grid[keep], track[:, 0], track[:, i + 1])
        ref = displacement[keep, i]
        correlation = float(np.corrcoef(ours, ref)[0, 1]) if ours.std() > 0 and ref.std() > 0 else float('nan')
        difference = float(np.sqrt(np.mean((ours - ref) ** 2)))
        published = float('nan')
        if variances is not None:
            variance = np.interp(grid[keep], variances[:, 0], variances[:, i + 1])
            # A point interpolated between a held output and a tracking one is left out too: its
            # variance is neither's.
            held = np.interp(grid[keep], variances[:, 0], (variances[:, i + 1] >= HELD_VARIANCE).astype(float))
            variance = variance[held == 0.0]
            published = float(np.sqrt(np.mean(variance))) if variance.size else float('nan')
        rows.append((axis, correlation, 4 * ours.std(), 4 * ref.std(), difference, published))
    return rows


NO_ORIENTATION_METHODS = (
    ('default, no orientation: one level frame', 'gyro_attitude: false\n'),
    ('default, no orientation: gyro attitude', 'gyro_attitude: true\nestimate_gyro_bias: false\n'),
    ('default, no orientation: gyro attitude, gyro bias estimated', 'gyro_attitude: true\nestimate_gyro_bias: true\n'))

REAL_SETS = (('xio_oscillatory', xio_oscillatory), ('xio_ngimu_heave_30cm', ngimu_heave),
             ('buoy_morro_bay', buoy_morro_bay), ('robot_arm_ground_truth', robot_arm))


def real(args):
    if not os.path.isdir(args.data):
        print('Real recordings: %s is absent, not measured.' % args.data)
        return
    ekf = built(args.robot_localization, EKF_NODE, "robot_localization's ekf_localization_node")
    madgwick = built(args.imu_tools, MADGWICK_NODE, "imu_tools' imu_filter_node")
    os.makedirs(args.work, exist_ok=True)
    devels = [d for d, node in ((args.robot_localization, ekf), (args.imu_tools, madgwick)) if node]
    ros = Ros(devels, args.work) if devels else None
    rows = []
    spectral = []
    try:
        for name, load in REAL_SETS:
            log('real data: %s' % name)
            t, accel, gyro, quat, rest = load(args.data)
            stem = os.path.join(args.work, name)
            write_imu_bag(stem + '.bag', t, accel, gyro, quat)
            tracks = {}
            waves = {}  # method: its output bag

            def compensate(method, bag, *extra):
                subprocess.run([os.path.join(args.bin, 'compensate_bag'), '--in', bag, '--out',
                                stem + '_%s.bag' % method] + list(extra), check=True,
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
                tracks[method] = position_track(stem + '_%s.bag' % method)
                waves[method] = stem + '_%s.bag' % method
            def paper_mode(method, settings):
                with open(stem + '_%s.yaml' % method, 'w') as f:
                    f.write('mode: paper\n' + settings)
                compensate(method, stem + '.bag', '--params', stem + '_%s.yaml' % method)
            paper_mode('raw', 'enable_constant: false\nenable_periodic: false\n')
            if rest:  # the constant bias from the recording's first REST seconds, at rest
                static = 'assume_static_calibration: true\ncalibration_duration: %g\n' % rest
                paper_mode('constant', static + 'enable_periodic: false\n')
                paper_mode('paper', static)
            compensate('default', stem + '.bag')
            gyro_logged = bool(abs(gyro).max() > 0)
            if gyro_logged:
                # The default mode as if the IMU reported no orientation: one level frame, or the
                # attitude from the gyro (gyro_attitude) without and with its bias estimated.
                write_imu_bag(stem + '_no_orientation.bag', t, accel, gyro, quat, orientation=False)
                for method, settings in NO_ORIENTATION_METHODS:
                    with open(stem + '_%s.yaml' % method, 'w') as f:
                        f.write(settings)
                    compensate(method, stem + '_no_orientation.bag', '--params', stem + '_%s.yaml' % method)
            if ros:
                odom, att, _, _, _ = replay(ros, stem + '.bag', ekf, madgwick if gyro_logged else None)
                if ekf:
                    write_odometry(odom, stem + '_ekf.bag')
                    tracks['robot_localization EKF'] = position_track(stem + '_ekf.bag')
                if madgwick and gyro_logged:
                    write_madgwick_input(stem + '.bag', att, stem + '_madgwick_in.bag')
                    compensate('Madgwick + default', stem + '_madgwick_in.bag')
            for method, (tt, total, slow) in tracks.items():
                value, what = real_errors(name, args.data, tt, total, slow)
                rows.append((name, what, method, value))
            if name in SPECTRAL_SETS:
                reference = spectral_displacement(t, accel, quat, SPECTRAL_SETS[name][0])
                for method in waves:
                    track = odometry_positions(waves[method]).get('odometry/wave')
                    if track is not None and 4 * track[:, 1:].std(0).max() >= 1e-3:  # methods with a wave output
                        variances = wave_variances(waves[method])
                        spectral.extend((name, method) + row
                                        for row in spectral_rows(name, reference, track, variances))
            for f in os.listdir(args.work):
                if f.startswith(name):
                    os.remove(os.path.join(args.work, f))
    finally:
        if ros:
            ros.close()
    print('| recording | error against its reference | method | error |')
    print('|---|---|---|---|')
    for name, what, method, value in rows:
        print('| %s | %s | %s | %.3f |' % (name, what, method, value))
    if spectral:
        print()
        print('Wave motion (`odometry/wave`) against a frequency-domain estimate of the same recording:')
        print('its specific force levelled by its own attitude, gravity off, divided by -(2 pi f)^2 in the')
        print('band (%s), over the part compared (%s).' % (
            '; '.join('%s %g-%g Hz' % (n, b[0], b[1]) for n, (b, _, _) in SPECTRAL_SETS.items()),
            '; '.join('%s from %g s to %g s before the end' % (n, a, e) for n, (_, a, e) in SPECTRAL_SETS.items())))
        print()
        print('RMS difference: of the two displacements; published std: the root of the mean position')
        print('variance `odometry/wave` gives, outputs held during the calibration window left out (the')
        print('difference also holds the frequency-domain estimate\'s own error).')
        print()
        print('| recording | method | axis | correlation | 4 x std, estimator [m] | 4 x std, frequency domain [m] '
              '| RMS difference [m] | published std [m] |')
        print('|---|---|---|---|---|---|---|---|')
        for name, method, axis, correlation, ours, ref, difference, published in spectral:
            print('| %s | %s | %s | %s | %.3f | %.3f | %.3f | %s |' % (
                name, method, axis, '-' if math.isnan(correlation) else '%.2f' % correlation, ours, ref,
                difference, '-' if math.isnan(published) else '%.3f' % published))


def throughput(args):
    ekf = built(args.robot_localization, EKF_NODE, "robot_localization's ekf_localization_node")
    if not ekf:
        return
    with tempfile.TemporaryDirectory() as work:
        ros = Ros([args.robot_localization], work)
        try:
            _, _, wall, cpu, sent = replay(ros, args.bag, ekf, None, args.seconds, lockstep=False)
        finally:
            ros.close()
    print('| program | messages | wall time [s] | messages per second (wall) | CPU time [s] | messages per CPU second |')
    print('|---|---|---|---|---|---|')
    print('| robot_localization ekf_localization_node (IMU alone) | %d | %.1f | %.3g | %.1f | %.3g |'
          % (sent, wall, sent / wall, cpu, sent / cpu))


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest='command', required=True)
    a = sub.add_parser('accuracy')
    a.add_argument('--bin', required=True, help='folder of simulate_imu, compensate_bag, evaluate_compensator')
    a.add_argument('--scenarios', nargs='+', required=True)
    a.add_argument('--seeds', type=int, default=3)
    a.add_argument('--work', required=True, help='folder for the bags')
    a.add_argument('--robot-localization', default=os.environ.get('PBC_ROBOT_LOCALIZATION'))
    a.add_argument('--imu-tools', default=os.environ.get('PBC_IMU_TOOLS'))
    r = sub.add_parser('real')
    r.add_argument('--bin', required=True, help='folder of compensate_bag')
    r.add_argument('--data', default=os.path.join(REPO, '../shared/data'))
    r.add_argument('--work', required=True, help='folder for the bags')
    r.add_argument('--robot-localization', default=os.environ.get('PBC_ROBOT_LOCALIZATION'))
    r.add_argument('--imu-tools', default=os.environ.get('PBC_IMU_TOOLS'))
    t = sub.add_parser('throughput')
    t.add_argument('--bag', required=True)
    t.add_argument('--seconds', type=float, help='replay only the first S seconds of the bag')
    t.add_argument('--robot-localization', default=os.environ.get('PBC_ROBOT_LOCALIZATION'))
    args = parser.parse_args()
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(1))  # stop the nodes and the master on the way out
    try:
        {'accuracy': accuracy, 'real': real, 'throughput': throughput}[args.command](args)
    except (RuntimeError, subprocess.CalledProcessError) as e:
        log('error: %s' % e)
        return 1
    return 0


if __name__ == '__main__':
    sys.exit(main())

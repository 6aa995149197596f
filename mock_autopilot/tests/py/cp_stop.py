#!/usr/bin/env python3
"""A pilot with a range sensor, for PX4's Collision Prevention: takes off, switches to Position mode, pushes
the pitch stick towards a virtual wall and reports the closest approach. The same script flies the mock and
PX4 SITL, so their stopping distances compare.

The wall stands across North, --wall m ahead of where Position mode starts. The sensor: OBSTACLE_DISTANCE in
the body frame, 5-degree sectors on PX4's bin grid, 90-degree field of view, 0.2-30 m. Sticks and scans go
out every 50 ms of vehicle time (--time-scale K: the vehicle runs K times faster than the wall clock).
Prints one line "stick X CP_DIST D: peak V m/s, closest C m, ..."; with --expect LO HI, exit 1 unless
LO <= closest <= HI. Every wait is bounded."""
import argparse
import math
import os
import sys
import time

os.environ["MAVLINK20"] = "1"
from pymavlink import mavutil  # noqa: E402

M = mavutil.mavlink
FOV, RMIN, RMAX = 90.0, 0.2, 30.0

ap = argparse.ArgumentParser()
ap.add_argument("--url", required=True, help="e.g. udpin:127.0.0.1:14540 (PX4 instance 0) or udpout:HOST:PORT")
ap.add_argument("--stick", type=int, default=1000, help="MANUAL_CONTROL x, -1000..1000")
ap.add_argument("--cp-dist", type=float, default=3.0)
ap.add_argument("--wall", type=float, default=25.0)
ap.add_argument("--push", type=float, default=30.0, help="vehicle seconds of stick towards the wall")
ap.add_argument("--time-scale", type=float, default=1.0)
ap.add_argument("--expect", type=float, nargs=2)
ap.add_argument("--trace", help="write vehicle time, distance to the wall and vx (CSV) here")
a = ap.parse_args()
K = a.time_scale

m = mavutil.mavlink_connection(a.url, source_system=255, source_component=190)
st = {"sys": 1, "x": 0.0, "vx": 0.0, "yaw": 0.0, "mode": None, "armed": False, "texts": []}
wall_x = None


def fail(msg):
    print("FAIL: " + msg + " " + " | ".join(st["texts"][-5:]))
    sys.exit(1)


def pump():
    while True:
        msg = m.recv_match(blocking=False)
        if msg is None:
            return
        t = msg.get_type()
        if t == "LOCAL_POSITION_NED":
            st.update(x=msg.x, vx=msg.vx)
        elif t == "ATTITUDE":
            st["yaw"] = msg.yaw
        elif t == "HEARTBEAT" and msg.get_srcSystem() == st["sys"] and msg.get_srcComponent() == 1:
            st["mode"] = ((msg.custom_mode >> 16) & 0xFF, (msg.custom_mode >> 24) & 0xFF)
            st["armed"] = bool(msg.base_mode & M.MAV_MODE_FLAG_SAFETY_ARMED)
        elif t == "STATUSTEXT":
            st["texts"].append(msg.text)


def scan():
    d = [65535] * 72
    for i in range(72):
        rel = (i * 5 + 180) % 360 - 180
        if abs(rel) > FOV / 2:
            continue
        c = math.cos(st["yaw"] + math.radians(rel))
        r = (wall_x - st["x"]) / c if (wall_x is not None and c > 1e-6) else math.inf
        d[i] = int(round(max(r, RMIN) * 100)) if r <= RMAX else int(RMAX * 100) + 1
    m.mav.obstacle_distance_send(0, M.MAV_DISTANCE_SENSOR_LASER, d, 5, int(RMIN * 100), int(RMAX * 100),
                                 0.0, 0.0, M.MAV_FRAME_BODY_FRD)


def fly(vehicle_secs, x, each=None):
    """Stick x (and scans) every 50 ms of vehicle time for vehicle_secs."""
    end = time.time() + vehicle_secs / K
    nxt = 0.0
    while time.time() < end:
        pump()
        if time.time() >= nxt:
            m.mav.manual_control_send(st["sys"], x, 0, 500, 0, 0)
            scan()
            nxt = time.time() + 0.05 / K
        if each:
            each()
        time.sleep(0.002)


def set_param(name, value):
    for _ in range(20):
        m.mav.param_set_send(st["sys"], 1, name.encode(), value, M.MAV_PARAM_TYPE_REAL32)
        end = time.time() + 0.5
        while time.time() < end:
            p = m.recv_match(type="PARAM_VALUE", blocking=True, timeout=0.1)
            if p and p.param_id == name and abs(p.param_value - value) < 1e-6:
                return
    fail(f"{name} not set")


def command(cmd, *p):
    p = list(p) + [0.0] * (7 - len(p))
    m.mav.command_long_send(st["sys"], 1, cmd, 0, *p)


for _ in range(100):
    m.mav.heartbeat_send(M.MAV_TYPE_GCS, M.MAV_AUTOPILOT_INVALID, 0, 0, 0)
    hb = m.recv_match(type="HEARTBEAT", blocking=True, timeout=0.3)
    if hb and hb.get_srcComponent() == 1:
        st["sys"] = hb.get_srcSystem()  # PX4 SITL instance i is system 1 + i
        break
else:
    fail("no heartbeat")
set_param("CP_DIST", a.cp_dist)
set_param("MIS_TAKEOFF_ALT", 5.0)
for _ in range(60):
    command(M.MAV_CMD_COMPONENT_ARM_DISARM, 1)
    fly(1.0 * K, 0)
    if st["armed"]:
        break
else:
    fail("not armed")
command(M.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, math.nan, math.nan, math.nan, math.nan)
fly(12, 0)
command(M.MAV_CMD_DO_SET_MODE, 1, 3, 0)
fly(3, 0)
if st["mode"] != (3, 0):
    fail(f"not in Position mode: {st['mode']}")
wall_x = st["x"] + a.wall
res = {"closest": math.inf, "peak": 0.0}
t0, trace = time.time(), []


def track():
    res["closest"] = min(res["closest"], wall_x - st["x"])
    res["peak"] = max(res["peak"], st["vx"])
    trace.append(((time.time() - t0) * K, wall_x - st["x"], st["vx"]))


fly(a.push, a.stick, track)
print(f"stick {a.stick} CP_DIST {a.cp_dist}: peak {res['peak']:.2f} m/s, closest {res['closest']:.2f} m, "
      f"end {wall_x - st['x']:.2f} m, mode {st['mode']}")
if a.trace:
    with open(a.trace, "w") as f:
        f.write("t_s,gap_m,vx_m_s\n" + "".join(f"{t:.3f},{g:.3f},{v:.3f}\n" for t, g, v in trace[::10]))
command(M.MAV_CMD_NAV_LAND)
fly(1, 0)
if a.expect and not (a.expect[0] <= res["closest"] <= a.expect[1]):
    fail(f"closest {res['closest']:.2f} m outside {a.expect}")

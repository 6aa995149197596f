#!/usr/bin/env python3
"""pymavlink GCS for the mock autopilot tests: uploads case-study mission 2, starts it, flies to
landing and checks the telemetry. With --expect-faults it checks --reject-mission 4 and --fail-arm.
Exit 0 on success; every wait is bounded."""
import argparse
import os
import struct
import sys
import time

os.environ["MAVLINK20"] = "1"
from pymavlink import mavutil  # noqa: E402

M = mavutil.mavlink
MISSION2 = [
    # (command, frame, param2, lat, lon, rel_alt)
    (530, M.MAV_FRAME_MISSION, 2.0, 0.0, 0.0, 0.0),
    (M.MAV_CMD_NAV_TAKEOFF, M.MAV_FRAME_GLOBAL_RELATIVE_ALT, 0.0, 47.3977419, 8.5455938, 10.0),
    (M.MAV_CMD_NAV_WAYPOINT, M.MAV_FRAME_GLOBAL_RELATIVE_ALT, 0.0, 47.39768051930175, 8.546310969707491, 10.0),
    (M.MAV_CMD_NAV_LAND, M.MAV_FRAME_GLOBAL_RELATIVE_ALT, 0.0, 47.39763082431753, 8.545595709237233, 0.0),
]


def fail(msg):
    print("FAIL: " + msg)
    sys.exit(1)


def recv(m, types, timeout):
    deadline = time.time() + timeout
    while time.time() < deadline:
        msg = m.recv_match(type=types, blocking=True, timeout=max(0.01, deadline - time.time()))
        if msg is not None:
            return msg
    return None


def upload(m):
    m.mav.mission_count_send(1, 1, len(MISSION2), M.MAV_MISSION_TYPE_MISSION)
    deadline = time.time() + 20
    last = None
    while time.time() < deadline:
        msg = recv(m, ["MISSION_REQUEST_INT", "MISSION_REQUEST", "MISSION_ACK"], 0.5)
        if msg is None:
            if last is None:
                m.mav.mission_count_send(1, 1, len(MISSION2), M.MAV_MISSION_TYPE_MISSION)
            else:
                last()
            continue
        if msg.get_type() == "MISSION_ACK":
            return msg.type
        cmd, frame, p2, lat, lon, alt = MISSION2[msg.seq]
        seq = msg.seq

        def send(seq=seq, cmd=cmd, frame=frame, p2=p2, lat=lat, lon=lon, alt=alt):
            m.mav.mission_item_int_send(1, 1, seq, frame, cmd, 0, 1, 0.0, p2, 0.0, float("nan"),
                                        int(round(lat * 1e7)), int(round(lon * 1e7)), alt,
                                        M.MAV_MISSION_TYPE_MISSION)
        send()
        last = send
    return None


def command(m, cmd, params):
    for _ in range(20):
        m.mav.command_long_send(1, 1, cmd, 0, *params)
        ack = recv(m, ["COMMAND_ACK"], 0.3)
        if ack is not None and ack.command == cmd:
            return ack.result
    return None


def wait_prearm(m, timeout):
    """PX4 v1.14 sets MAV_SYS_STATUS_PREARM_CHECK in SYS_STATUS health once its arming checks pass (estimator
    settled); before that it refuses to start a mission, so a client waits, as QGroundControl's "Ready to fly"."""
    deadline = time.time() + timeout
    while time.time() < deadline:
        st = recv(m, ["SYS_STATUS"], max(0.01, deadline - time.time()))
        if st is not None and st.onboard_control_sensors_health & M.MAV_SYS_STATUS_PREARM_CHECK:
            return True
    return False


def fly(m):
    # Parameters come typed as PX4 sends them (INT32 bytewise).
    m.mav.param_request_read_send(1, 1, b"GF_ACTION", -1)
    pv = recv(m, ["PARAM_VALUE"], 3)
    if pv is None or pv.param_type != M.MAV_PARAM_TYPE_INT32:
        fail("GF_ACTION not INT32: %s" % pv)
    if struct.unpack("<i", struct.pack("<f", pv.param_value))[0] != 2:
        fail("GF_ACTION bytewise value")
    code = upload(m)
    if code != M.MAV_MISSION_ACCEPTED:
        fail("upload result %s" % code)
    if not wait_prearm(m, 30):
        fail("pre-arm checks never passed (SYS_STATUS)")
    if command(m, M.MAV_CMD_MISSION_START, [0] * 7) != M.MAV_RESULT_ACCEPTED:
        fail("MISSION_START not accepted")
    reached, landed_states, max_rel_alt, texts = set(), [], 0.0, []
    armed_seen, n_local, t0 = False, 0, time.time()
    while time.time() - t0 < 40:
        msg = recv(m, ["HEARTBEAT", "MISSION_ITEM_REACHED", "EXTENDED_SYS_STATE", "GLOBAL_POSITION_INT",
                       "LOCAL_POSITION_NED", "STATUSTEXT"], 1.0)
        if msg is None:
            continue
        t = msg.get_type()
        if t == "MISSION_ITEM_REACHED":
            reached.add(msg.seq)
        elif t == "EXTENDED_SYS_STATE":
            if not landed_states or landed_states[-1] != msg.landed_state:
                landed_states.append(msg.landed_state)
        elif t == "GLOBAL_POSITION_INT":
            max_rel_alt = max(max_rel_alt, msg.relative_alt / 1000.0)
        elif t == "LOCAL_POSITION_NED":
            n_local += 1
        elif t == "STATUSTEXT":
            texts.append(msg.text)
        elif t == "HEARTBEAT" and msg.autopilot == M.MAV_AUTOPILOT_PX4:
            armed = bool(msg.base_mode & M.MAV_MODE_FLAG_SAFETY_ARMED)
            armed_seen |= armed
            if armed_seen and not armed:
                break
    else:
        fail("no disarm within 40 s; reached %s" % sorted(reached))
    if sorted(reached) != [0, 1, 2, 3]:
        fail("reached %s" % sorted(reached))
    if not 9.0 <= max_rel_alt <= 11.0:
        fail("max relative altitude %.2f" % max_rel_alt)
    want = [M.MAV_LANDED_STATE_ON_GROUND, M.MAV_LANDED_STATE_TAKEOFF, M.MAV_LANDED_STATE_IN_AIR,
            M.MAV_LANDED_STATE_LANDING, M.MAV_LANDED_STATE_ON_GROUND]
    if landed_states != want:
        fail("landed states %s" % landed_states)
    if "Landing detected" not in texts:
        fail("texts %s" % texts)
    if n_local < 100:
        fail("only %d LOCAL_POSITION_NED" % n_local)
    print("MISSION OK reached=%s max_alt=%.2f local=%d" % (sorted(reached), max_rel_alt, n_local))


def faults(m):
    code = upload(m)
    if code != M.MAV_MISSION_NO_SPACE:
        fail("expected NO_SPACE (4), got %s" % code)
    res = command(m, M.MAV_CMD_COMPONENT_ARM_DISARM, [1, 0, 0, 0, 0, 0, 0])
    if res != M.MAV_RESULT_TEMPORARILY_REJECTED:
        fail("arming result %s" % res)
    print("FAULTS OK")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--port", type=int, required=True)
    ap.add_argument("--expect-faults", action="store_true")
    a = ap.parse_args()
    m = mavutil.mavlink_connection("udpout:127.0.0.1:%d" % a.port, source_system=255, source_component=190,
                                   dialect="common")
    hb = None
    for _ in range(50):
        m.mav.heartbeat_send(M.MAV_TYPE_GCS, M.MAV_AUTOPILOT_INVALID, 0, 0, 0)
        hb = recv(m, ["HEARTBEAT"], 0.2)
        if hb is not None:
            break
    if hb is None or hb.autopilot != M.MAV_AUTOPILOT_PX4 or hb.type != M.MAV_TYPE_QUADROTOR:
        fail("no PX4 quadrotor heartbeat: %s" % hb)
    if (hb.custom_mode >> 16) & 0xFF != 4:
        fail("custom_mode main mode %d" % ((hb.custom_mode >> 16) & 0xFF))
    faults(m) if a.expect_faults else fly(m)


if __name__ == "__main__":
    main()

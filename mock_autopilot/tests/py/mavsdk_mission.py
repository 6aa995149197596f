"""MAVSDK (MAVSDK-Python over its bundled mavsdk_server, the gRPC client most PX4 users script with) flies
the mock unchanged: connect, health, upload and download a mission, arm, fly it, land, disarm.

Usage: mavsdk_mission.py --port MOCK_UDP_PORT
Prints "MAVSDK OK" on success; every wait is bounded.
"""

import argparse
import asyncio
import math
import socket
import sys

from mavsdk_grpc import System
from mavsdk_grpc.mission import MissionItem, MissionPlan

M_PER_DEG_LAT = 111_320.0


def free_port() -> int:
    # mavsdk_server's gRPC port must not be fixed either, or parallel tests collide.
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


async def first(stream, pred, what, timeout):
    async def wait():
        async for v in stream:
            if pred(v):
                return v
        raise RuntimeError(f"{what}: stream ended")

    try:
        return await asyncio.wait_for(wait(), timeout)
    except asyncio.TimeoutError:
        raise RuntimeError(f"{what}: not within {timeout} s") from None


def item(lat, lon, alt):
    return MissionItem(
        lat, lon, alt, 5.0, True, math.nan, math.nan,
        MissionItem.CameraAction.NONE, math.nan, math.nan, 1.0, math.nan, math.nan,
        MissionItem.VehicleAction.NONE,
    )


async def fly(port: int) -> None:
    drone = System(port=free_port())
    await drone.connect(system_address=f"udpout://127.0.0.1:{port}")
    await first(drone.core.connection_state(), lambda s: s.is_connected, "connection", 30)
    print("connected")
    await first(
        drone.telemetry.health(),
        lambda h: h.is_global_position_ok and h.is_home_position_ok,
        "health (global position and home)",
        30,
    )
    home = await first(drone.telemetry.home(), lambda h: not math.isnan(h.latitude_deg), "home", 10)
    dlat = 30.0 / M_PER_DEG_LAT
    dlon = 20.0 / (M_PER_DEG_LAT * math.cos(math.radians(home.latitude_deg)))
    items = [
        item(home.latitude_deg + dlat, home.longitude_deg, 10.0),
        item(home.latitude_deg + dlat, home.longitude_deg + dlon, 10.0),
        item(home.latitude_deg, home.longitude_deg + dlon, 10.0),
    ]
    await drone.mission.set_return_to_launch_after_mission(False)
    await drone.mission.upload_mission(MissionPlan(items))
    got = await drone.mission.download_mission()
    if len(got.mission_items) != len(items):
        raise RuntimeError(f"downloaded {len(got.mission_items)} items, uploaded {len(items)}")
    for a, b in zip(items, got.mission_items):
        if abs(a.latitude_deg - b.latitude_deg) > 1e-6 or abs(a.longitude_deg - b.longitude_deg) > 1e-6:
            raise RuntimeError(f"item changed in the round trip: {a} -> {b}")
    print("mission uploaded and read back")
    await drone.action.arm()
    await drone.mission.start_mission()
    await first(drone.telemetry.in_air(), lambda a: a, "taking off", 30)
    await first(
        drone.mission.mission_progress(),
        lambda p: p.total > 0 and p.current == p.total,
        "mission progress to the end",
        120,
    )
    pos = await first(drone.telemetry.position(), lambda p: True, "position", 10)
    print(f"mission finished at alt {pos.relative_altitude_m:.1f} m")
    await drone.action.land()
    await first(drone.telemetry.in_air(), lambda a: not a, "landing", 120)
    await first(drone.telemetry.armed(), lambda a: not a, "auto-disarm after landing", 60)
    print("MAVSDK OK")


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--port", type=int, required=True)
    args = ap.parse_args()
    try:
        asyncio.run(asyncio.wait_for(fly(args.port), 300))
    except Exception as e:  # report any failure with its reason, exit non-zero
        print(f"MAVSDK FAILED: {type(e).__name__}: {e}")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())

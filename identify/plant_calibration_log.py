#!/usr/bin/env python3
"""A noise-free calibration log of the full plant, for the identifier's model-error check: the
sticks of a tello_pilot calibration log (its rc datagrams, relative to the takeoff's ok) flown by
`shelfcross plant` (the plant and autopilot with default parameters: gains 1, 1, 1.5, time
constants 0.5, 0.4, 0.3 s; no link, no wind, no dead time), written back as a tello_pilot log:
state records every 100 ms, rounded as the SDK rounds (dm/s, cm, degrees).
   plant_calibration_log.py SHELFCROSS SOURCE_LOG OUT_LOG
Then `shelfcross identify --log OUT_LOG --out DIR`: what it finds against those defaults is the
model's own error (docs/calibration.md, "The model's own error")."""
import csv
import json
import math
import subprocess
import sys

shelfcross, source, out = sys.argv[1:4]
TAKEOFF_AT_S = 0.5
rc, takeoff_ok, land = [], None, None
with open(source) as f:
    for line in f:
        j = json.loads(line)
        if j["type"] == "reply" and j.get("command") == "takeoff" and j.get("reply") == "ok" and takeoff_ok is None:
            takeoff_ok = j["t_ns"] / 1e9
        elif j["type"] == "rc_sent":
            rc.append((j["t_ns"] / 1e9, j["command"]))
        elif j["type"] == "sent" and j.get("command") == "land" and land is None:
            land = j["t_ns"] / 1e9
if takeoff_ok is None or land is None:
    sys.exit(f"{source}: no takeoff 'ok' or no 'land' sent")

# The plant's own takeoff 'ok': fly the takeoff alone first.
with open(out + ".takeoff", "w") as f:
    f.write(f"0 command\n{TAKEOFF_AT_S} takeoff\n")
done = subprocess.run([shelfcross, "plant", "--commands", out + ".takeoff", "--seconds", "10", "--out", out + ".csv"],
                      check=True, capture_output=True, text=True)
ok_s = float(next(l.split()[0] for l in done.stderr.splitlines() if l.endswith("-> ok") and "deferred" in l))
shift = ok_s - takeoff_ok
commands = ["0 command", f"{TAKEOFF_AT_S} takeoff"]
sticks = []
for t, text in rc:
    t_plant = round((t + shift) / 0.002) * 0.002  # the autopilot's 500 Hz ticks
    if t_plant > ok_s:
        sticks.append((t_plant, text))
        commands.append(f"{t_plant:.3f} {text}")
land_s = land + shift
commands.append(f"{land_s:.3f} land")
with open(out + ".commands", "w") as f:
    f.write("\n".join(commands) + "\n")
subprocess.run([shelfcross, "plant", "--commands", out + ".commands", "--seconds", f"{land_s + 1:.1f}", "--out",
                out + ".csv", "--rate", "10"], check=True, capture_output=True)

lines = []


def put(t, kind, **fields):
    record = {"t_s": t, "t_ns": int(round(t * 1e9)), "type": kind}
    record.update(fields)
    lines.append((t, len(lines), json.dumps(record)))


def sdk_round(v):  # lround: halves away from zero
    return int(math.copysign(math.floor(abs(v) + 0.5), v))


put(0.001, "start", mode="calibration_flight")
put(ok_s + 0.001, "reply", command="takeoff", reply="ok", attempt=1, origin="fsw")
for t, text in sticks:
    put(t, "rc_sent", command=text)
with open(out + ".csv") as f:
    rows = list(csv.DictReader(f))
floor_z = float(rows[0]["z_m"])
for r in rows:
    t = float(r["t_s"])
    if t < 0.1:
        continue
    yaw, vx, vy, vz = (float(r[k]) for k in ("yaw_rad", "vx_mps", "vy_mps", "vz_mps"))
    vx_H, vy_H = math.cos(yaw) * vx + math.sin(yaw) * vy, -math.sin(yaw) * vx + math.cos(yaw) * vy
    h = float(r["z_m"]) - floor_z
    deg = 180.0 / math.pi
    raw = (f"mid:-1;x:-100;y:-100;z:-100;mpry:-1,-1,-1;pitch:{sdk_round(-float(r['pitch_rad']) * deg)};"
           f"roll:{sdk_round(float(r['roll_rad']) * deg)};yaw:{sdk_round(-yaw * deg)};vgx:{sdk_round(vx_H * 10)};"
           f"vgy:{sdk_round(-vy_H * 10)};vgz:{sdk_round(-vz * 10)};templ:55;temph:57;tof:{sdk_round(h * 100 + 10)};"
           f"h:{sdk_round(h * 100)};bat:90;baro:100.00;time:1;agx:0.00;agy:0.00;agz:-1000.00;")
    put(t + 0.0001, "state", raw=raw, battery_pct=90, height_m=h)
put(land_s, "sent", command="land", attempt=1, origin="pilot")
put(land_s + 2.0, "end", exit_code=0)
lines.sort()
with open(out, "w") as f:
    f.write("".join(l[2] + "\n" for l in lines))

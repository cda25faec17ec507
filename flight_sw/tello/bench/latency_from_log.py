#!/usr/bin/env python3
"""Latency of tello_pilot from its flight log (JSON lines), as flight_sw/tello/README.md reports it:

  receive: a frame's last datagram in (frame.rx_ns) -> decoded frame in the mailbox (frame.handed_ns)
  taken:   mailbox -> taken by the main loop (frame.t_ns)
  step:    decoded frame -> the flight software returned its rc (taken + FlightSoftware::step)
  answer:  decoded frame -> the rc datagram that carries the flight software's answer to it leaves
           the socket (rc_sent.t_ns): the flight software's rc whose fsw_t_ns is the frame's stamp,
           matched to the first rc_sent of that text at or after it. "changed" answers differ from
           the sticks already on the wire and go out at once; "same" answers only renew the
           setpoint and ride on the driver's steady 100 ms repeat.

usage: latency_from_log.py FLIGHT_LOG.jsonl
"""
import json
import sys


def pct(values, p):
    if not values:
        return float("nan")
    v = sorted(values)
    k = min(len(v) - 1, max(0, int(round(p / 100.0 * (len(v) - 1)))))
    return v[k]


def show(name, values_ns):
    ms = [x / 1e6 for x in values_ns]
    print(f"{name:<34} n={len(ms):5d}  p50={pct(ms, 50):7.2f} ms  p99={pct(ms, 99):7.2f} ms  max={max(ms) if ms else float('nan'):7.2f} ms")


def main():
    lines = [json.loads(l) for l in open(sys.argv[1]) if l.strip()]
    frames = {}
    receive, taken = [], []
    for j in lines:
        if j["type"] == "frame":
            receive.append(j["handed_ns"] - j["rx_ns"])
            taken.append(j["t_ns"] - j["handed_ns"])
            frames[j["handed_ns"]] = j
    changed, same, step, driver = [], [], [], []
    on_wire = None  # the sticks last sent
    pending = []    # (frame handed_ns, text, changed?, answered_ns) awaiting their rc_sent
    for j in lines:
        if j["type"] == "fsw_command" and j["text"].startswith("rc ") and j["fsw_t_ns"] in frames:
            step.append(j["t_ns"] - j["fsw_t_ns"])
            pending.append((j["fsw_t_ns"], j["text"], j["text"] != on_wire, j["t_ns"]))
        elif j["type"] in ("rc_sent", "keepalive"):
            on_wire = j["command"]
            rest = []
            for handed, text, is_changed, answered in pending:
                if text == j["command"]:
                    (changed if is_changed else same).append(j["t_ns"] - handed)
                    if is_changed:
                        driver.append(j["t_ns"] - answered)
                elif j["t_ns"] - handed < 2_000_000_000:
                    rest.append((handed, text, is_changed, answered))
            pending = rest
    show("last datagram -> decoded, handed", receive)
    show("handed -> taken by the main loop", taken)
    show("handed -> flight software's rc", step)
    show("its rc -> rc out (changed sticks)", driver)
    show("handed -> rc out (changed sticks)", changed)
    show("handed -> rc out (same sticks)", same)
    show("handed -> rc out (all answers)", changed + same)


if __name__ == "__main__":
    main()

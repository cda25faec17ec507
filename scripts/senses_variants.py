#!/usr/bin/env python3
"""Scenario variants with the Tello's senses one effect at a time, for paired campaigns.

    senses_variants.py EFFECTS.yaml OUT_DIR [--onto SCENARIO.yaml ...]

EFFECTS.yaml is a scenario carrying every effect at its documented values and dispersions
(scenarios/paper_test_shelf.yaml, the default; every shipped scenario carries them). For it,
OUT_DIR/<effect>.yaml keeps that one effect and drops the others, and OUT_DIR/none.yaml drops
them all; so none.yaml flies the world without the senses and each <effect>.yaml the world with
one. For each --onto SCENARIO,
OUT_DIR/<stem>_none.yaml is that scenario without any effect and OUT_DIR/<stem>_all.yaml the
same with every effect of EFFECTS.yaml added. Every variant keeps its source's `name`, so
`shelfcross diff` pairs campaigns of two variants run by run. Each campaign draws every
dispersion from its own stream, so dropping or adding an effect's dispersions leaves every other
draw of a run as it was.

The effects (scenarios/README.md): the VPS and the position hold on it; the tof, h and baro
readings' noise and drift; the height hold following the range reading; the camera's rolling
shutter; the ground and ceiling effect.
"""
import argparse
import copy
import pathlib
import sys

import yaml

# effect: (key paths in the scenario, dispersion names)
EFFECTS = {
    "vps": ([("senses", "vps")],
            ["vps_min_range_m", "vps_floor_texture", "vps_box_texture", "vps_bar_texture",
             "vps_noise_mps", "vps_bias_stddev_mps"]),
    "readings": ([("senses", "height")],
                 ["tof_noise_m", "height_noise_m", "baro_noise_m", "baro_drift_m_per_sqrt_s"]),
    "height_hold": ([("senses", "height_hold")],
                    ["height_hold_range_blend", "height_hold_range_below_m",
                     "height_hold_time_constant_s"]),
    "rolling_shutter": ([("camera", "readout_s")], ["camera_readout_s"]),
    "surface_effects": ([("vehicle", "surface_effects")],
                        ["ground_effect_coeff", "ceiling_effect_coeff"]),
}
# Keys every sense shares: kept while any senses effect is on, dropped with the last.
SHARED_SENSES = ("senses", "sample_rate_hz")


def drop(doc, effect):
    paths, dispersions = EFFECTS[effect]
    for section, key in paths:
        doc.get(section, {}).pop(key, None)
    for name in dispersions:
        doc.get("dispersions", {}).pop(name, None)
    senses = doc.get("senses")
    if senses is not None and set(senses) <= {SHARED_SENSES[1]}:
        del doc["senses"]


def add(doc, source, effect):
    paths, dispersions = EFFECTS[effect]
    for section, key in paths:
        if key in source.get(section, {}):
            doc.setdefault(section, {})[key] = copy.deepcopy(source[section][key])
        if section == SHARED_SENSES[0] and SHARED_SENSES[1] in source.get(section, {}):
            doc[section].setdefault(SHARED_SENSES[1], source[section][SHARED_SENSES[1]])
    for name in dispersions:
        if name in source.get("dispersions", {}):
            doc.setdefault("dispersions", {})[name] = copy.deepcopy(source["dispersions"][name])


def write(path, doc, what):
    header = (f"# {what}\n# Written by scripts/senses_variants.py; every key as in its source "
              "(scenarios/README.md).\n")
    path.write_text(header + yaml.safe_dump(doc, sort_keys=False, default_flow_style=None, width=100))
    print(path)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("effects", type=pathlib.Path)
    ap.add_argument("out", type=pathlib.Path)
    ap.add_argument("--onto", type=pathlib.Path, action="append", default=[])
    args = ap.parse_args()
    source = yaml.safe_load(args.effects.read_text())
    for effect in EFFECTS:
        paths, _ = EFFECTS[effect]
        if not any(key in source.get(section, {}) for section, key in paths):
            sys.exit(f"{args.effects}: effect {effect} ({paths}) not in the scenario")
    args.out.mkdir(parents=True, exist_ok=True)
    none = copy.deepcopy(source)
    for effect in EFFECTS:
        drop(none, effect)
    write(args.out / "none.yaml", none, f"{args.effects} without any effect of the senses")
    for effect in EFFECTS:
        one = copy.deepcopy(none)
        add(one, source, effect)
        write(args.out / f"{effect}.yaml", one, f"{args.effects} with the effect {effect} alone")
    for target in args.onto:
        doc = yaml.safe_load(target.read_text())
        for effect in EFFECTS:
            drop(doc, effect)
        write(args.out / f"{target.stem}_none.yaml", doc, f"{target} without any effect of the senses")
        for effect in EFFECTS:
            add(doc, source, effect)
        write(args.out / f"{target.stem}_all.yaml", doc,
              f"{target} with every effect of {args.effects}")


if __name__ == "__main__":
    main()

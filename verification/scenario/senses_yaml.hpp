#pragma once
// The scenario's `senses:` section (plant/tello_senses.hpp): the Tello's vision positioning
// system, its height and range sensors and its height hold's source. Walked by scenario.cpp's
// Reader and Writer like every other section; internal to scenario/.

#include "plant/tello_senses.hpp"
#include "verification/scenario/scenario_yaml.hpp"

namespace shelfcross::verification::scenario_yaml {

template <class V>
void visit_senses(V& v, plant::SensesParams& p) {
  v.field("sample_rate_hz", p.sample_rate_hz, between(1.0, 1000.0));
  v.section("vps", [&](auto& s) {
    plant::VpsParams& q = p.vps;
    s.field("min_range_m", q.min_range_m, between(0.0, 10.0));
    s.field("max_range_m", q.max_range_m, between(0.0, 100.0));
    s.check("max_range_m", q.max_range_m >= q.min_range_m, "must not be below min_range_m");
    s.field("min_contrast", q.min_contrast, kUnit);
    s.section("texture", [&](auto& t) {
      t.field("floor", q.texture.floor, kUnit);
      t.field("box", q.texture.box, kUnit);
      t.field("bar", q.texture.bar, kUnit);
      t.field("tag", q.texture.tag, kUnit);
      t.field("wall", q.texture.wall, kUnit);
    });
    s.field("noise_mps", q.noise_mps, between(0.0, 1.0));
    s.field("bias_stddev_mps", q.bias_stddev_mps, between(0.0, 1.0));
    s.field("bias_time_constant_s", q.bias_time_constant_s, between(0.1, 3600.0));
  });
  v.section("height", [&](auto& s) {
    plant::HeightSensorParams& q = p.height;
    s.field("tof_max_range_m", q.tof_max_range_m, between(0.1, 100.0));
    s.field("tof_ground_m", q.tof_ground_m, between(0.0, 1.0));
    s.field("tof_noise_m", q.tof_noise_m, between(0.0, 1.0));
    s.field("height_noise_m", q.height_noise_m, between(0.0, 1.0));
    s.field("baro_noise_m", q.baro_noise_m, between(0.0, 5.0));
    s.field("baro_drift_m_per_sqrt_s", q.baro_drift_m_per_sqrt_s, between(0.0, 1.0));
  });
  v.section("height_hold", [&](auto& s) {
    plant::HeightHoldParams& q = p.height_hold;
    s.field("range_blend", q.range_blend, kUnit);
    s.field("range_below_m", q.range_below_m, between(0.0, 100.0));
    s.field("time_constant_s", q.time_constant_s, between(0.01, 60.0));
  });
}

}  // namespace shelfcross::verification::scenario_yaml

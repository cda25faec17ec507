#include "plant/quadrotor.hpp"

#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <sstream>

#include "plant/wind.hpp"

namespace shelfcross::plant {

// The CVODE integrator's handles, freed together; the state vector y is the integrator's own.
struct CvodeSolver {
  SUNContext ctx = nullptr;
  N_Vector y = nullptr;
  N_Vector abstol = nullptr;
  void* cvode = nullptr;
  SUNNonlinearSolver nls = nullptr;
  SUNMatrix jac = nullptr;
  SUNLinearSolver ls = nullptr;
  std::string last_error;  // CVODE's last message, for the failure report

  CvodeSolver() = default;
  CvodeSolver(const CvodeSolver&) = delete;
  CvodeSolver& operator=(const CvodeSolver&) = delete;
  ~CvodeSolver() {
    if (cvode) CVodeFree(&cvode);
    if (nls) SUNNonlinSolFree(nls);
    if (ls) SUNLinSolFree(ls);
    if (jac) SUNMatDestroy(jac);
    if (abstol) N_VDestroy(abstol);
    if (y) N_VDestroy(y);
    if (ctx) SUNContext_Free(&ctx);
  }

  static void error_handler(int /*code*/, const char* module, const char* function, char* msg, void* user) {
    auto* self = static_cast<CvodeSolver*>(user);
    self->last_error = std::string(module) + "::" + function + ": " + msg;
  }

  static void check(int flag, const char* what) {
    if (flag < 0) throw std::runtime_error(std::string("plant: CVODE setup failed in ") + what);
  }

  // The integrator from state y0 with the given right-hand side and one root function, both
  // called with `user`.
  void create(const IntegratorSettings& settings, const RigidBodyState& y0, CVRhsFn rhs, CVRootFn root,
              void* user) {
    check(SUNContext_Create(nullptr, &ctx), "SUNContext_Create");
    y = N_VNew_Serial(kStateSize, ctx);
    abstol = N_VNew_Serial(kStateSize, ctx);
    if (!y || !abstol) throw std::runtime_error("plant: N_VNew_Serial failed");
    N_VEnableFusedOps_Serial(y, SUNTRUE);  // fewer passes over the 17 components per step
    double* a = N_VGetArrayPointer(abstol);
    for (int i = 0; i < kStateSize; ++i) {
      a[i] = i >= kIdxRotor ? settings.abs_tol_rotor_radps
             : i >= kIdxW   ? settings.abs_tol_rate_radps
                            : settings.abs_tol;
    }
    pack_state(y0, N_VGetArrayPointer(y));
    const bool adams = settings.method == IntegratorSettings::Method::adams_fixed_point;
    cvode = CVodeCreate(adams ? CV_ADAMS : CV_BDF, ctx);
    if (!cvode) throw std::runtime_error("plant: CVodeCreate failed");
    check(CVodeSetErrHandlerFn(cvode, &CvodeSolver::error_handler, this), "CVodeSetErrHandlerFn");
    check(CVodeInit(cvode, rhs, 0.0, y), "CVodeInit");
    check(CVodeSVtolerances(cvode, settings.rel_tol, abstol), "CVodeSVtolerances");
    check(CVodeSetUserData(cvode, user), "CVodeSetUserData");
    check(CVodeSetMaxNumSteps(cvode, settings.max_steps_per_segment), "CVodeSetMaxNumSteps");
    if (adams) {
      nls = SUNNonlinSol_FixedPoint(y, 0, ctx);
      check(CVodeSetNonlinearSolver(cvode, nls), "CVodeSetNonlinearSolver");
    } else {
      jac = SUNDenseMatrix(kStateSize, kStateSize, ctx);
      ls = SUNLinSol_Dense(y, jac, ctx);
      check(CVodeSetLinearSolver(cvode, ls, jac), "CVodeSetLinearSolver");
    }
    check(CVodeRootInit(cvode, 1, root), "CVodeRootInit");
    check(CVodeSetNoInactiveRootWarn(cvode), "CVodeSetNoInactiveRootWarn");
  }
};

struct Quadrotor::Impl {
  VehicleParams vehicle;
  IntegratorSettings settings;
  WindModel wind;
  CvodeSolver solver;

  RigidBodyState state;
  TimeNs t_ns = 0;
  Eigen::Vector4d cmd = Eigen::Vector4d::Zero();
  Eigen::Vector4d thrust_factor = Eigen::Vector4d::Ones();
  Eigen::Vector3d wind_W = Eigen::Vector3d::Zero();
  bool on_floor = false;
  long rhs_count = 0;

  Impl(const VehicleParams& v, const WindParams& w, std::uint64_t seed, IntegratorSettings s)
      : vehicle(v), settings(s), wind(w, seed) {}

  double rest_z() const { return vehicle.floor_z_m + vehicle.rest_height_m(); }

  // Vertical force balance on the resting vehicle: thrust along z_W minus weight (N).
  double liftoff_margin(const double* yv) const {
    const double b = vehicle.thrust_coeff_N_per_radps2;
    double o2 = 0.0;
    for (int i = 0; i < 4; ++i) o2 += yv[kIdxRotor + i] * yv[kIdxRotor + i] * thrust_factor[i];
    const Eigen::Quaterniond q(yv[kIdxQ], yv[kIdxQ + 1], yv[kIdxQ + 2], yv[kIdxQ + 3]);
    const double r33 = q.normalized().toRotationMatrix()(2, 2);
    return b * o2 * r33 - vehicle.mass_kg * vehicle.gravity_mps2;
  }

  static int rhs(realtype /*t*/, N_Vector yv, N_Vector ydotv, void* user) {
    auto* self = static_cast<Impl*>(user);
    ++self->rhs_count;
    const double* yp = N_VGetArrayPointer(yv);
    double* yd = N_VGetArrayPointer(ydotv);
    for (int i = 0; i < kStateSize; ++i)
      if (!std::isfinite(yp[i])) return -1;  // unrecoverable: CVode reports CV_RHSFUNC_FAIL
    rigid_body_rhs(self->vehicle, yp, self->cmd, self->wind_W, yd, self->thrust_factor);
    if (self->on_floor)  // held by the floor: only the rotors move
      for (int i = 0; i < kIdxRotor; ++i) yd[i] = 0.0;
    return 0;
  }

  static int root(realtype /*t*/, N_Vector yv, realtype* g, void* user) {
    auto* self = static_cast<Impl*>(user);
    const double* yp = N_VGetArrayPointer(yv);
    g[0] = self->on_floor ? self->liftoff_margin(yp) : yp[kIdxP + 2] - self->rest_z();
    return 0;
  }

  void create() { solver.create(settings, state, &Impl::rhs, &Impl::root, this); }

  // Plastic touchdown: rest on the floor, level, keeping yaw; rotors unchanged.
  void settle_on_floor(double* yp) {
    RigidBodyState s = unpack_state(yp);
    const double yaw = euler_zyx_from_quaternion(s.q_WB).z();
    s.p_WB_m.z() = rest_z();
    s.v_WB_W_mps.setZero();
    s.w_WB_B_radps.setZero();
    s.q_WB = quaternion_from_euler_zyx(0.0, 0.0, yaw);
    pack_state(s, yp);
    on_floor = true;
  }

  // Contact transitions decided at the start of a segment (the root functions catch them
  // inside a segment).
  void update_contact(double* yp) {
    if (on_floor) {
      if (liftoff_margin(yp) > 0.0) on_floor = false;
    } else if (yp[kIdxP + 2] < rest_z() ||
               (yp[kIdxP + 2] == rest_z() && yp[kIdxV + 2] <= 0.0 && liftoff_margin(yp) <= 0.0)) {
      settle_on_floor(yp);
    }
  }

  void fail(int flag, const std::string& why) {
    std::ostringstream os;
    os << "plant: numerical failure at t = " << ns_to_seconds(t_ns) << " s: " << why;
    if (!solver.last_error.empty()) os << " (" << solver.last_error << ")";
    throw NumericalFailure(t_ns, flag, os.str());
  }

  void advance_to(TimeNs t_target) {
    assert(t_target >= t_ns);
    double* yp = N_VGetArrayPointer(solver.y);
    int events_here = 0;
    while (t_ns < t_target) {
      update_contact(yp);
      wind_W = wind.wind_W_mps(t_ns);
      // Segment time runs from 0 so that CVODE's real time keeps full resolution.
      const double dt = ns_to_seconds(t_target - t_ns);
      int flag = CVodeReInit(solver.cvode, 0.0, solver.y);
      if (flag >= 0) flag = CVodeSetStopTime(solver.cvode, dt);
      int direction = on_floor ? +1 : -1;  // lift-off: margin rising; touchdown: z falling
      if (flag >= 0) flag = CVodeSetRootDirection(solver.cvode, &direction);
      if (flag >= 0 && settings.initial_step_s >= 0.0)
        flag = CVodeSetInitStep(solver.cvode, settings.initial_step_s > 0.0 ? std::min(settings.initial_step_s, dt) : dt);
      if (flag < 0) fail(flag, "re-initialisation");
      realtype t_reached = 0.0;
      flag = CVode(solver.cvode, dt, solver.y, &t_reached, CV_NORMAL);
      if (flag < 0) fail(flag, "CVode returned " + std::to_string(flag));
      for (int i = 0; i < kStateSize; ++i)
        if (!std::isfinite(yp[i])) fail(0, "non-finite state");
      // Keep the quaternion on the unit sphere between segments.
      const double qn = std::sqrt(yp[kIdxQ] * yp[kIdxQ] + yp[kIdxQ + 1] * yp[kIdxQ + 1] +
                                  yp[kIdxQ + 2] * yp[kIdxQ + 2] + yp[kIdxQ + 3] * yp[kIdxQ + 3]);
      for (int i = 0; i < 4; ++i) yp[kIdxQ + i] /= qn;
      if (flag == CV_ROOT_RETURN) {
        const TimeNs t_event = t_ns + std::min<TimeNs>(t_target - t_ns, seconds_to_ns(t_reached));
        events_here = t_event == t_ns ? events_here + 1 : 0;
        if (events_here > 4) fail(0, "contact chattering");
        t_ns = t_event;
        if (on_floor) {
          on_floor = false;
        } else {
          settle_on_floor(yp);
        }
      } else {
        t_ns = t_target;
      }
    }
    if (on_floor) yp[kIdxP + 2] = rest_z();
    state = unpack_state(yp);
  }
};

Quadrotor::Quadrotor(const VehicleParams& vehicle, const WindParams& wind, std::uint64_t wind_seed,
                     IntegratorSettings settings) {
  const auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  if (!positive(vehicle.mass_kg) || !positive(vehicle.inertia_kgm2.minCoeff()) || !positive(vehicle.arm_x_m) ||
      !positive(vehicle.arm_y_m) || !positive(vehicle.thrust_coeff_N_per_radps2) ||
      !positive(vehicle.torque_coeff_Nm_per_radps2) || !positive(vehicle.rotor_speed_max_radps) ||
      !positive(vehicle.motor_time_constant_s) || !positive(vehicle.size_m.minCoeff()) ||
      !(vehicle.rotor_inertia_kgm2 >= 0.0) || !(vehicle.linear_drag_Ns_per_m.minCoeff() >= 0.0) ||
      !(vehicle.quadratic_drag_Ns2_per_m2.minCoeff() >= 0.0))
    throw std::invalid_argument("plant: vehicle parameters must be positive (drag and Jr >= 0)");
  if (!positive(settings.rel_tol) || !positive(settings.abs_tol) || !positive(settings.abs_tol_rate_radps) ||
      !positive(settings.abs_tol_rotor_radps))
    throw std::invalid_argument("plant: integrator tolerances must be positive");
  impl_ = std::make_unique<Impl>(vehicle, wind, wind_seed, settings);
  impl_->state = landed_state(vehicle);
  impl_->on_floor = true;
  impl_->create();
}

Quadrotor::~Quadrotor() = default;
Quadrotor::Quadrotor(Quadrotor&&) noexcept = default;
Quadrotor& Quadrotor::operator=(Quadrotor&&) noexcept = default;

RigidBodyState Quadrotor::landed_state(const VehicleParams& vehicle, double x_m, double y_m, double yaw_rad) {
  RigidBodyState s;
  s.p_WB_m = Eigen::Vector3d(x_m, y_m, vehicle.floor_z_m + vehicle.rest_height_m());
  s.q_WB = quaternion_from_euler_zyx(0.0, 0.0, yaw_rad);
  return s;
}

void Quadrotor::reset(const RigidBodyState& state, TimeNs t_ns) {
  Impl& m = *impl_;
  m.state = state;
  m.state.q_WB.normalize();
  m.t_ns = t_ns;
  m.cmd = state.rotor_speed_radps;
  double* yp = N_VGetArrayPointer(m.solver.y);
  pack_state(m.state, yp);
  m.on_floor = false;
  if (yp[kIdxP + 2] <= m.rest_z()) m.settle_on_floor(yp);
  m.state = unpack_state(yp);
}

void Quadrotor::set_rotor_commands(const Eigen::Vector4d& cmd_radps) {
  Impl& m = *impl_;
  for (int i = 0; i < 4; ++i) {
    const double c = cmd_radps[i];
    m.cmd[i] = std::isfinite(c) ? std::clamp(c, 0.0, m.vehicle.rotor_speed_max_radps) : 0.0;
  }
  if (!m.vehicle.switches.motor_dynamics) {
    double* yp = N_VGetArrayPointer(m.solver.y);
    for (int i = 0; i < 4; ++i) yp[kIdxRotor + i] = m.cmd[i];
    m.state.rotor_speed_radps = m.cmd;
  }
}

void Quadrotor::set_rotor_thrust_factors(const Eigen::Vector4d& factors) { impl_->thrust_factor = factors; }
const Eigen::Vector4d& Quadrotor::rotor_thrust_factors() const { return impl_->thrust_factor; }

void Quadrotor::advance_to(TimeNs t_ns) { impl_->advance_to(t_ns); }
const RigidBodyState& Quadrotor::state() const { return impl_->state; }
TimeNs Quadrotor::time_ns() const { return impl_->t_ns; }
const Eigen::Vector4d& Quadrotor::rotor_commands() const { return impl_->cmd; }
bool Quadrotor::on_floor() const { return impl_->on_floor; }
Eigen::Vector3d Quadrotor::wind_W_mps() const { return impl_->wind_W; }
const VehicleParams& Quadrotor::vehicle() const { return impl_->vehicle; }
long Quadrotor::rhs_evaluations() const { return impl_->rhs_count; }

}  // namespace shelfcross::plant

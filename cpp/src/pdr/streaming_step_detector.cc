// Streaming step detector (streaming_step_detector.h). Every arithmetic expression keeps the
// operation order of the reference it replaced (python indoorloc.pdr.streaming before it called
// this), so causal steps and the figures built on them did not move.
#include "indoorloc/pdr/streaming_step_detector.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

#include "indoorloc/core/check.h"
#include "indoorloc/pdr/stride_length.h"

namespace indoorloc::pdr {
namespace {

constexpr double kGravityMps2 = 9.80665;  // python indoorloc.pdr.orientation.GRAVITY_MPS2
constexpr double kPi = 3.14159265358979323846;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Python's float a % b for b > 0 (fmod, then the sign of the divisor).
double PyMod(double a, double b) {
  double m = std::fmod(a, b);
  if (m != 0.0) {
    if ((b < 0) != (m < 0)) m += b;
  } else {
    m = std::copysign(0.0, b);
  }
  return m;
}

// Angle folded into [-pi, pi).
double Wrap(double a) { return PyMod(a + kPi, 2.0 * kPi) - kPi; }

// Second-order sections run one sample at a time (transposed direct form II), started in the
// steady state of the first input.
class Sos {
 public:
  Sos() = default;
  explicit Sos(const RowMatrixXd& sos) {
    for (Eigen::Index r = 0; r < sos.rows(); ++r) {
      const double a0 = sos(r, 3);
      sections_.push_back({sos(r, 0) / a0, sos(r, 1) / a0, sos(r, 2) / a0, sos(r, 4) / a0, sos(r, 5) / a0});
    }
  }
  bool empty() const { return sections_.empty(); }
  double operator()(double x) {
    if (!started_) {  // the steady state of a constant input x
      started_ = true;
      double v = x;
      for (const Section& s : sections_) {
        const double y0 = v * (s.b0 + s.b1 + s.b2) / (1.0 + s.a1 + s.a2);
        state_.push_back({y0 - s.b0 * v, s.b2 * v - s.a2 * y0});
        v = y0;
      }
    }
    for (std::size_t i = 0; i < sections_.size(); ++i) {
      const Section& s = sections_[i];
      std::pair<double, double>& st = state_[i];
      const double y = s.b0 * x + st.first;
      st.first = s.b1 * x - s.a1 * y + st.second;
      st.second = s.b2 * x - s.a2 * y;
      x = y;
    }
    return x;
  }

 private:
  struct Section {
    double b0, b1, b2, a1, a2;
  };
  std::vector<Section> sections_;
  std::vector<std::pair<double, double>> state_;
  bool started_ = false;
};

struct Sample {
  double t;
  Eigen::Vector3d acc, gyro;
  Eigen::Vector4d quat;
};

// What the detector remembers of a recent sample: time, index, low-passed |a|, heading integrals
// (rv, gyro, complementary) and headings.
struct Recent {
  double t;
  long long index;
  double lp;
  double integral[3];
  double heading[3];
};

}  // namespace

bool StreamingStepOptions::IsValid(std::string* error) const {
  auto fail = [error](const std::string& m) {
    if (error) *error = m;
    return false;
  };
  auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  if (!positive(lowpass_hz)) return fail("lowpass_hz must be finite and > 0");
  if (!positive(highpass_hz) || highpass_hz >= lowpass_hz) return fail("highpass_hz must be finite, > 0 and < lowpass_hz");
  if (filter_order < 1 || filter_order > 8) return fail("filter_order must be in [1, 8]");
  if (!positive(rms_window_s)) return fail("rms_window_s must be finite and > 0");
  if (!(std::isfinite(threshold_fraction) && threshold_fraction >= 0)) return fail("threshold_fraction must be finite and >= 0");
  if (!(std::isfinite(min_peak_mps2) && min_peak_mps2 >= 0)) return fail("min_peak_mps2 must be finite and >= 0");
  if (!positive(min_step_interval_s)) return fail("min_step_interval_s must be finite and > 0");
  if (!positive(max_step_half_window_s)) return fail("max_step_half_window_s must be finite and > 0");
  if (!positive(complementary_tau_s)) return fail("complementary_tau_s must be finite and > 0");
  if (rate_samples < 1 || rate_samples > 100000) return fail("rate_samples must be in [1, 100000]");
  return true;
}

Eigen::Vector4d QuaternionFromRotationVector(const Eigen::Ref<const Eigen::VectorXd>& values) {
  CheckArgument(values.size() >= 3, "values", "expected 3 or 4 rotation-vector values");
  for (int i = 0; i < 3; ++i) CheckArgument(std::isfinite(values[i]), "values", "x, y, z must be finite");
  Eigen::Vector4d q;
  const double x = values[0], y = values[1], z = values[2];
  q << x, y, z, std::sqrt(std::max(0.0, 1.0 - (x * x + y * y + z * z)));
  if (values.size() >= 4 && !std::isnan(values[3])) q[3] = values[3];
  const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  return norm > 0 ? Eigen::Vector4d(q / norm) : q;
}

struct StreamingStepDetector::State {
  StreamingStepOptions o;
  std::vector<Sample> buffer;  // samples before the rate is known
  double rate_hz = kNaN;
  long long n = 0;             // samples processed (the index of the next one)
  double last_t = -std::numeric_limits<double>::infinity();
  double first_t = kNaN;
  Sos lp, hp, comp;
  std::deque<std::pair<double, double>> rms;  // (t, s²) over the trailing window
  double rms_sum = 0.0;
  std::deque<Recent> recent;
  int seen = 0;                // band-passed samples so far (s_prev2 / s_prev valid when >= 2 / 1)
  double s_prev2 = 0, s_prev = 0, thr_prev = std::numeric_limits<double>::infinity(), t_prev = kNaN;
  bool has_candidate = false;
  double cand_t = 0, cand_value = 0;
  long long cand_index = 0;
  bool has_last_step = false;
  double last_step[4] = {0, 0, 0, 0};  // (t, I_rv, I_gyro, I_comp)
  bool has_heading = false;
  double raw_prev = 0, h_prev[3] = {0, 0, 0}, w_prev = 0;
  double integral[3] = {0, 0, 0};

  void StartFilters() {
    const int order = o.filter_order;
    lp = Sos(ButterworthSos(order, std::min(o.lowpass_hz, 0.45 * rate_hz), rate_hz));
    hp = Sos(ButterworthSos(order, o.highpass_hz, rate_hz, true));
    const double fc = 1.0 / (2.0 * kPi * o.complementary_tau_s);
    if (fc < 0.45 * rate_hz) comp = Sos(ButterworthSos(1, fc, rate_hz));
  }

  void Process(const Sample& smp, std::vector<StreamingStep>* out);
  StreamingStep Confirm();
};

void StreamingStepDetector::State::Process(const Sample& smp, std::vector<StreamingStep>* out) {
  const double t = smp.t;
  const long long i = n++;
  if (std::isnan(first_t)) first_t = t;
  const Eigen::Vector3d& a = smp.acc;
  const double mag = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]) - kGravityMps2;
  const double lpv = lp(mag);
  const double s = hp(lpv);
  // Headings (header, 6) and their running integrals (trapezoid).
  const double x = smp.quat[0], y = smp.quat[1], z = smp.quat[2], w = smp.quat[3];
  const Eigen::Vector3d& g = smp.gyro;
  const double raw = std::atan2(1.0 - 2.0 * (x * x + z * z), 2.0 * (x * y - w * z));
  const double w_up = (2.0 * (x * z - w * y)) * g[0] + (2.0 * (y * z + w * x)) * g[1] + (1.0 - 2.0 * (x * x + y * y)) * g[2];
  double h_rv = raw, h_gy = raw;
  if (has_heading) {
    const double dt = t - t_prev;
    h_rv = h_prev[0] + Wrap(raw - raw_prev);
    h_gy = h_prev[1] + 0.5 * (w_prev + w_up) * dt;
  }
  const double h_c = comp.empty() ? h_rv : h_gy + comp(h_rv - h_gy);
  if (has_heading) {
    const double dt = t - t_prev;
    integral[0] = integral[0] + 0.5 * (h_prev[0] + h_rv) * dt;
    integral[1] = integral[1] + 0.5 * (h_prev[1] + h_gy) * dt;
    integral[2] = integral[2] + 0.5 * (h_prev[2] + h_c) * dt;
  }
  has_heading = true;
  raw_prev = raw;
  h_prev[0] = h_rv;
  h_prev[1] = h_gy;
  h_prev[2] = h_c;
  w_prev = w_up;
  recent.push_back({t, i, lpv, {integral[0], integral[1], integral[2]}, {h_rv, h_gy, h_c}});
  const double keep_s = 3.0 * o.max_step_half_window_s + 2.0 * o.min_step_interval_s + 1.0;
  while (!recent.empty() && recent.front().t < t - keep_s) recent.pop_front();
  // Trailing RMS and threshold.
  rms.emplace_back(t, s * s);
  rms_sum += s * s;
  while (rms.front().first < t - o.rms_window_s) {
    rms_sum -= rms.front().second;
    rms.pop_front();
  }
  const double thr = std::max(o.threshold_fraction * std::sqrt(std::max(rms_sum, 0.0) / static_cast<double>(rms.size())),
                              o.min_peak_mps2);
  // Sample i - 1 a local maximum above its threshold: a candidate.
  if (seen >= 2 && s_prev > s_prev2 && s_prev >= s && s_prev >= thr_prev) {
    const double tp = t_prev;
    const bool far = !has_last_step || tp - last_step[0] >= o.min_step_interval_s;
    if (far && (!has_candidate || s_prev > cand_value)) {
      has_candidate = true;
      cand_t = tp;
      cand_index = i - 1;
      cand_value = s_prev;
    }
  }
  if (has_candidate && t - cand_t >= o.min_step_interval_s) {
    out->push_back(Confirm());
    out->back().confirmed_time_s = t;
    has_candidate = false;
  }
  s_prev2 = s_prev;
  s_prev = s;
  thr_prev = thr;
  t_prev = t;
  ++seen;
}

StreamingStep StreamingStepDetector::State::Confirm() {
  const double tc = cand_t;
  const double hw = o.max_step_half_window_s;
  const double half = !has_last_step ? hw : std::min(hw, 0.5 * (tc - last_step[0]));
  const double lo_t = tc - half, hi_t = tc + half;
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  bool any = false;
  const Recent* at_c = nullptr;
  for (const Recent& r : recent) {
    if (lo_t <= r.t && r.t <= hi_t) {
      lo = std::min(lo, r.lp);
      hi = std::max(hi, r.lp);
      any = true;
    }
    if (r.index == cand_index && at_c == nullptr) at_c = &r;
  }
  if (at_c == nullptr) throw std::logic_error("indoorloc: StreamingStepDetector: the candidate's sample was forgotten");
  const double feature = any ? std::pow(std::max(0.0, hi - lo), 0.25) : 0.0;
  double start[4] = {0, 0, 0, 0};
  if (!has_last_step) {  // the first step: the interval before it
    const double t_a = std::max(first_t, tc - 2.0 * hw);
    const Recent* a = at_c;
    for (const Recent& r : recent) {
      if (r.t >= t_a) {
        a = &r;
        break;
      }
    }
    start[0] = a->t;
    for (int j = 0; j < 3; ++j) start[1 + j] = a->integral[j];
  } else {
    std::copy(last_step, last_step + 4, start);
  }
  const double width = tc - start[0];
  double heads[3];
  for (int j = 0; j < 3; ++j) heads[j] = width > 1e-9 ? (at_c->integral[j] - start[1 + j]) / width : at_c->heading[j];
  StreamingStep step;
  step.time_s = tc;
  step.index = cand_index;
  step.feature = feature;
  step.heading_rotation_vector_rad = Wrap(heads[0]);
  step.heading_gyro_rad = Wrap(heads[1]);
  step.heading_complementary_rad = Wrap(heads[2]);
  step.start_time_s = start[0];
  has_last_step = true;
  last_step[0] = tc;
  for (int j = 0; j < 3; ++j) last_step[1 + j] = at_c->integral[j];
  return step;
}

StreamingStepDetector::StreamingStepDetector(const StreamingStepOptions& options) : state_(std::make_unique<State>()) {
  std::string error;
  if (!options.IsValid(&error)) ThrowInvalidArgument("options", error);
  state_->o = options;
}
StreamingStepDetector::~StreamingStepDetector() = default;
StreamingStepDetector::StreamingStepDetector(StreamingStepDetector&&) noexcept = default;
StreamingStepDetector& StreamingStepDetector::operator=(StreamingStepDetector&&) noexcept = default;

int StreamingStepDetector::AddSample(double time_s, const Eigen::Vector3d& acc_mps2, const Eigen::Vector3d& gyro_radps,
                                     const Eigen::Vector4d& quat_xyzw, std::vector<StreamingStep>* steps) {
  State& st = *state_;
  CheckArgument(std::isfinite(time_s), "t_s", "must be finite, got " + std::to_string(time_s));
  if (!(time_s > st.last_t)) {
    ThrowInvalidArgument("t_s", "sample at t = " + std::to_string(time_s) + " s is not after the previous one (t = " +
                                    std::to_string(st.last_t) + " s)");
  }
  CheckArgument(acc_mps2.allFinite(), "acc_mps2", "must be finite");
  CheckArgument(gyro_radps.allFinite(), "gyro_radps", "must be finite");
  CheckArgument(quat_xyzw.allFinite(), "quat_xyzw", "must be finite");
  std::vector<StreamingStep> local;
  std::vector<StreamingStep>* out = steps ? steps : &local;
  const std::size_t before = out->size();
  st.last_t = time_s;
  const Sample sample{time_s, acc_mps2, gyro_radps, quat_xyzw};
  if (std::isnan(st.rate_hz)) {
    st.buffer.push_back(sample);
    if (static_cast<int>(st.buffer.size()) <= st.o.rate_samples) return 0;
    std::vector<double> dt(st.buffer.size() - 1);
    for (std::size_t k = 0; k + 1 < st.buffer.size(); ++k) dt[k] = st.buffer[k + 1].t - st.buffer[k].t;
    std::sort(dt.begin(), dt.end());
    const std::size_t m = dt.size();
    const double median = m % 2 ? dt[m / 2] : (dt[m / 2 - 1] + dt[m / 2]) / 2.0;
    st.rate_hz = 1.0 / median;
    st.StartFilters();
    for (const Sample& s : st.buffer) st.Process(s, out);
    st.buffer.clear();
    st.buffer.shrink_to_fit();
  } else {
    st.Process(sample, out);
  }
  return static_cast<int>(out->size() - before);
}

double StreamingStepDetector::rate_hz() const { return state_->rate_hz; }
double StreamingStepDetector::first_time_s() const {
  return state_->first_t;
}
double StreamingStepDetector::latest_time_s() const { return state_->last_t; }
const StreamingStepOptions& StreamingStepDetector::options() const { return state_->o; }

std::vector<StreamingStep> CausalSteps(const Eigen::Ref<const Eigen::VectorXd>& time_s,
                                       const Eigen::Ref<const Eigen::MatrixXd>& acc_mps2,
                                       const Eigen::Ref<const Eigen::MatrixXd>& gyro_radps,
                                       const Eigen::Ref<const Eigen::MatrixXd>& quat_xyzw,
                                       const StreamingStepOptions& options) {
  const Eigen::Index n = time_s.size();
  CheckShape(acc_mps2, n, 3, "acc_mps2");
  CheckShape(gyro_radps, n, 3, "gyro_radps");
  CheckShape(quat_xyzw, n, 4, "quat_xyzw");
  StreamingStepDetector detector(options);
  std::vector<StreamingStep> out;
  for (Eigen::Index k = 0; k < n; ++k) {
    try {
      detector.AddSample(time_s[k], acc_mps2.row(k).transpose(), gyro_radps.row(k).transpose(),
                         quat_xyzw.row(k).transpose(), &out);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(std::string(e.what()) + " (sample " + std::to_string(k) + ")");
    }
  }
  return out;
}

}  // namespace indoorloc::pdr

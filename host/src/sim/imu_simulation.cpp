// Synthetic IMU readings and GPS-like position priors along a SplineTrajectory. Tangent conventions are those of
// trajectory.cpp: gyro readings are body rates ([w]x = R^T dR/dt), rotations update on the right.
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "vkloc/core/random.hpp"
#include "vkloc/core/se3.hpp"
#include "vkloc/sim/trajectory.hpp"

namespace vkloc {
namespace {

bool finiteNonNegative(double x) { return std::isfinite(x) && x >= 0.0; }

/// Sample times start + round(k / rate) (ns) up to and including the end.
std::vector<int64_t> sampleTimes(int64_t start_ns, int64_t end_ns, double rate_hz) {
  std::vector<int64_t> times;
  if (!std::isfinite(rate_hz) || rate_hz <= 0.0 || end_ns < start_ns) return times;
  const double period_ns = 1e9 / rate_hz;
  const double count = std::floor(static_cast<double>(end_ns - start_ns) / period_ns + 1e-9) + 1.0;
  if (count > 1e8) return times;  // Refuse absurd sizes instead of exhausting memory.
  times.reserve(static_cast<size_t>(count));
  for (int64_t k = 0;; ++k) {
    const int64_t t = start_ns + static_cast<int64_t>(std::llround(static_cast<double>(k) * period_ns));
    if (t > end_ns) break;
    times.push_back(t);
  }
  return times;
}

}  // namespace

std::vector<ImuSample> simulateImu(const SplineTrajectory& trajectory, const std::optional<ImuNoise>& noise,
                                   const Eigen::Vector3d& gravity_world, uint64_t seed) {
  const ImuNoise params = noise.value_or(ImuNoise{});
  if (!gravity_world.allFinite() || !finiteNonNegative(params.gyro_noise_density) ||
      !finiteNonNegative(params.accel_noise_density) || !finiteNonNegative(params.gyro_random_walk) ||
      !finiteNonNegative(params.accel_random_walk)) {
    return {};
  }
  const std::vector<int64_t> times = sampleTimes(trajectory.startNs(), trajectory.endNs(), params.rate_hz);
  // Discrete-time equivalents (Kalibr "IMU noise model"): white sigma_d = density sqrt(rate),
  // bias random-walk step sigma_b = rw / sqrt(rate).
  const double sqrt_rate = std::sqrt(params.rate_hz);
  const double gyro_sigma = params.gyro_noise_density * sqrt_rate;
  const double accel_sigma = params.accel_noise_density * sqrt_rate;
  const double gyro_walk = params.gyro_random_walk / sqrt_rate;
  const double accel_walk = params.accel_random_walk / sqrt_rate;
  Mt19937 engine(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  auto draw = [&]() { return Eigen::Vector3d(normal(engine), normal(engine), normal(engine)); };
  Eigen::Vector3d gyro_bias = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_bias = Eigen::Vector3d::Zero();
  std::vector<ImuSample> samples;
  samples.reserve(times.size());
  for (int64_t t : times) {
    const TrajectoryState s = trajectory.evaluate(t);
    ImuSample sample;
    sample.t_ns = t;
    sample.gyro_body = s.omega_body;
    sample.accel_body = s.T_world_body.linear().transpose() * (s.a_world_body - gravity_world);
    if (noise) {
      // Fixed draw order per sample: gyro noise, accel noise, gyro bias step, accel bias step.
      sample.gyro_body += gyro_bias + gyro_sigma * draw();
      sample.accel_body += accel_bias + accel_sigma * draw();
      gyro_bias += gyro_walk * draw();
      accel_bias += accel_walk * draw();
    }
    samples.push_back(sample);
  }
  return samples;
}

std::vector<PositionPrior> simulatePriors(const SplineTrajectory& trajectory, const PriorOptions& options,
                                          uint64_t seed) {
  if (!options.sigma.allFinite() || options.sigma.minCoeff() <= 0.0 || !std::isfinite(options.dropout_probability) ||
      options.dropout_probability < 0.0 || options.dropout_probability > 1.0 ||
      !finiteNonNegative(options.dropout_mean_s)) {
    return {};
  }
  const std::vector<int64_t> times = sampleTimes(trajectory.startNs(), trajectory.endNs(), options.rate_hz);
  Mt19937 engine(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::vector<PositionPrior> priors;
  int64_t dropout_end_ns = std::numeric_limits<int64_t>::min();
  for (int64_t t : times) {
    if (t < dropout_end_ns) continue;  // Inside a dropout: no fix, no random draws.
    if (uniform(engine) < options.dropout_probability) {
      // This fix is lost and so are all fixes within an exponentially distributed duration.
      const double length_s = -options.dropout_mean_s * std::log(1.0 - uniform(engine));
      dropout_end_ns = t + static_cast<int64_t>(std::llround(std::min(length_s, 1e6) * 1e9));
      continue;
    }
    PositionPrior prior;
    prior.t_ns = t;
    const Eigen::Vector3d noise(normal(engine), normal(engine), normal(engine));
    prior.p_world_body = trajectory.evaluate(t).T_world_body.translation() + options.sigma.cwiseProduct(noise);
    prior.sigma = options.sigma;
    priors.push_back(prior);
  }
  return priors;
}

}  // namespace vkloc

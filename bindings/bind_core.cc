// Python bindings of indoorloc's core: random streams, log-weights, resampling.
#include <cstdint>
#include <string>
#include <vector>

#include <pybind11/stl.h>

#include "indoorloc/core.h"
#include "indoorloc/core/interrupt.h"
#include "indoorloc/core/validate.h"
#include "numpy_args.h"
#include "options_binding.h"

namespace indoorloc::bindings {
namespace {

py::array_t<std::int64_t> ToNumpyIndices(const std::vector<int>& indices) {
  py::array_t<std::int64_t> out(static_cast<py::ssize_t>(indices.size()));
  std::int64_t* data = out.mutable_data();
  for (size_t k = 0; k < indices.size(); ++k) data[k] = indices[k];
  return out;
}

// `rng` may be a RandomStream (advanced in place) or an int seed (a fresh stream 0).
template <typename Fn>
auto WithStream(const py::object& rng, Fn fn) {
  if (py::isinstance<RandomStream>(rng)) return fn(rng.cast<RandomStream&>());
  if (py::isinstance<py::int_>(rng) && !py::isinstance<py::bool_>(rng)) {
    // A seed outside uint64 would give pybind11's "Unable to cast ... to C++ type '?'".
    CheckArgument(rng.attr("__ge__")(0).cast<bool>() && rng.attr("__lt__")(py::int_(1).attr("__lshift__")(64)).cast<bool>(),
                  "rng", "an int seed must be in [0, 2**64)");
    RandomStream stream(rng.cast<std::uint64_t>());
    return fn(stream);
  }
  ThrowInvalidArgument("rng", "expected an indoorloc.core.RandomStream or an int seed");
}

template <typename Draw>
py::array_t<double> DrawMany(RandomStream& rng, py::ssize_t size, const char* name, Draw draw) {
  CheckArgument(size >= 0, name, "must be >= 0");
  RequireSizeLimit(static_cast<double>(size), sizeof(double), name, "draws");
  py::array_t<double> out(size);
  double* data = out.mutable_data();
  {
    py::gil_scoped_release release;
    for (py::ssize_t k = 0; k < size; ++k) {
      if ((k & 0xFFFFF) == 0) CheckInterrupt();  // Ctrl-C every ~1e6 draws
      data[k] = draw();
    }
  }
  return out;
}

}  // namespace

/// Seeds and the counter-based random streams.
static void BindRandomStreams(py::module_& m) {
  m.def("derive_seed", &DeriveSeed, py::arg("seed"), py::arg("stream"),
        "Seed of stream `stream` derived from `seed` (SplitMix64 hash); both are uint64.");

  py::class_<RandomStream>(m, "RandomStream", R"doc(
Seeded xoshiro256++ random stream. ``RandomStream(seed, stream=0)``: distinct (seed, stream)
pairs are independent; the same pair always gives the same numbers on every platform.)doc")
      .def(py::init<std::uint64_t, std::uint64_t>(), py::arg("seed") = 0, py::arg("stream") = 0)
      .def("uniform", [](RandomStream& r, py::ssize_t size) {
             return DrawMany(r, size, "size", [&] { return r.Uniform01(); });
           }, py::arg("size"), "Array of `size` uniform draws on [0, 1).")
      .def("normal", [](RandomStream& r, py::ssize_t size) {
             return DrawMany(r, size, "size", [&] { return r.Normal(); });
           }, py::arg("size"), "Array of `size` standard normal draws.")
      .def("von_mises", [](RandomStream& r, double mu_rad, double kappa, py::ssize_t size) {
             RequireFinite(mu_rad, "mu_rad");
             CheckNonNegative(kappa, "kappa");
             return DrawMany(r, size, "size", [&] { return r.VonMises(mu_rad, kappa); });
           }, py::arg("mu_rad"), py::arg("kappa"), py::arg("size"),
           "Array of `size` von Mises draws in (-pi, pi] [rad], mean `mu_rad`, concentration kappa >= 0.")
      .def("integers", [](RandomStream& r, std::uint64_t n, py::ssize_t size) {
             CheckArgument(n > 0, "n", "must be > 0");
             CheckArgument(size >= 0, "size", "must be >= 0");
             RequireSizeLimit(static_cast<double>(size), sizeof(std::int64_t), "size", "draws");
             py::array_t<std::int64_t> out(size);
             auto* data = out.mutable_data();
             for (py::ssize_t k = 0; k < size; ++k) {
               if ((k & 0xFFFFF) == 0) CheckInterrupt();  // Ctrl-C every ~1e6 draws
               data[k] = static_cast<std::int64_t>(r.UniformInt(n));
             }
             return out;
           }, py::arg("n"), py::arg("size"), "Array of `size` uniform integers in [0, n).")
      .def("split", &RandomStream::Split, py::arg("child"),
           "An independent child stream derived from this one (this stream advances one draw).");
}

/// Log-weight arithmetic: log-sum-exp, normalisation, ESS.
static void BindLogWeights(py::module_& m) {
  m.def("log_sum_exp", [](const py::object& log_weights) {
          // C++ validates log-weights itself (NaN, +inf, all -inf), naming the entry.
          VectorArg lw = ToVector(log_weights, "log_weights", -1, Finiteness::kAny);
          return LogSumExp(lw.map);
        }, py::arg("log_weights"),
        "log(sum(exp(log_weights))), computed stably. -inf entries are zero weights.");

  m.def("normalize_log_weights", [](const py::object& log_weights) {
          // C++ validates log-weights itself (NaN, +inf, all -inf), naming the entry.
          VectorArg lw = ToVector(log_weights, "log_weights", -1, Finiteness::kAny);
          Eigen::VectorXd out = lw.map;
          const double log_normalizer = NormalizeLogWeights(out);
          return py::make_tuple(ToNumpy(out), log_normalizer);
        }, py::arg("log_weights"), R"doc(
Normalise log-weights. Returns ``(normalized_log_weights, log_normalizer)`` where
``log_normalizer = log(sum(exp(log_weights)))``. The input is not modified.)doc");

  m.def("effective_sample_size", [](const py::object& log_weights) {
          // C++ validates log-weights itself (NaN, +inf, all -inf), naming the entry.
          VectorArg lw = ToVector(log_weights, "log_weights", -1, Finiteness::kAny);
          return EffectiveSampleSize(lw.map);
        }, py::arg("log_weights"),
        "Effective sample size (sum w)^2 / sum w^2 of unnormalised log-weights, in [1, N].");
}

/// Resampling schemes, adaptive resampling and its options.
static void BindResampling(py::module_& m) {
  m.def("resample", [](const py::object& log_weights, const std::string& scheme,
                       const py::object& rng, int num_out) {
          // C++ validates log-weights itself (NaN, +inf, all -inf), naming the entry.
          VectorArg lw = ToVector(log_weights, "log_weights", -1, Finiteness::kAny);
          const ResamplingScheme s = ParseResamplingScheme(scheme);
          std::vector<int> ancestors;
          WithStream(rng, [&](RandomStream& stream) {
            py::gil_scoped_release release;
            Resample(lw.map, s, stream, &ancestors, num_out);
            return 0;
          });
          return ToNumpyIndices(ancestors);
        }, py::arg("log_weights"), py::arg("scheme") = "systematic", py::arg("rng") = 0,
        py::arg("num_out") = -1, R"doc(
Resample particles from log-weights.

Parameters
----------
log_weights : (N,) float array
    Unnormalised log-weights; -inf means weight zero.
scheme : {"systematic", "stratified", "residual", "multinomial"}
rng : RandomStream or int
    Stream to draw from (advanced in place), or a seed.
num_out : int
    Number of draws; -1 for N.

Returns
-------
(num_out,) int64 array of ancestor indices, sorted.)doc");

  m.def("offspring_counts", [](const py::object& log_weights, const std::string& scheme,
                               int n_runs, std::uint64_t seed, int n_threads) {
          // C++ validates log-weights itself (NaN, +inf, all -inf), naming the entry.
          VectorArg lw = ToVector(log_weights, "log_weights", -1, Finiteness::kAny);
          const ResamplingScheme s = ParseResamplingScheme(scheme);
          CheckArgument(n_runs >= 0, "n_runs", "must be >= 0");
          const Eigen::Index n = lw.map.size();
          CheckArgument(n > 0, "log_weights", "is empty");
          RequireSizeLimit(static_cast<double>(n_runs) * static_cast<double>(n), sizeof(std::int64_t), "n_runs",
                           "counts (n_runs x len(log_weights))");
          py::array_t<std::int64_t> counts({static_cast<py::ssize_t>(n_runs), static_cast<py::ssize_t>(n)});
          std::int64_t* data = counts.mutable_data();
          std::fill(data, data + n_runs * n, 0);
          {
            py::gil_scoped_release release;
            ParallelForRuns(n_runs, n_threads, seed, [&](int run, RandomStream& rng) {
              std::vector<int> ancestors;
              Resample(lw.map, s, rng, &ancestors);
              for (int a : ancestors) ++data[run * n + a];
            });
          }
          return counts;
        }, py::arg("log_weights"), py::arg("scheme") = "systematic", py::arg("n_runs") = 1000,
        py::arg("seed") = 0, py::arg("n_threads") = 0, R"doc(
Offspring counts of `n_runs` independent resamplings, run r using stream (seed, r).

Returns an (n_runs, N) int64 array. The result depends only on the seed, never on n_threads
(0 = all cores). Used to check unbiasedness (mean count = N w) and compare scheme variances.)doc");

  py::class_<ResamplingOptions> resampling_options(
      m, "ResamplingOptions",
      "Options of adaptive resampling (resample when ESS < ess_threshold * N); fields by keyword.");
  resampling_options
      .def_property("scheme", [](const ResamplingOptions& o) { return std::string(ToString(o.scheme)); },
                    [](ResamplingOptions& o, const std::string& s) { o.scheme = ParseResamplingScheme(s); },
                    "'multinomial', 'stratified', 'systematic' or 'residual'.")
      .def_readwrite("ess_threshold", &ResamplingOptions::ess_threshold, "Resample when ESS < this * N.");
  BindOptionsProtocol(resampling_options, "ResamplingOptions", {"scheme", "ess_threshold"});

  py::class_<ResamplingSummary>(m, "ResamplingSummary", "What one adaptive resampling step did.")
      .def_readonly("resampled", &ResamplingSummary::resampled)
      .def_readonly("num_particles", &ResamplingSummary::num_particles)
      .def_readonly("ess_before", &ResamplingSummary::ess_before)
      .def_readonly("log_normalizer", &ResamplingSummary::log_normalizer)
      .def_readonly("num_unique_ancestors", &ResamplingSummary::num_unique_ancestors)
      .def("brief_report", &ResamplingSummary::BriefReport)
      .def("__repr__", [](const ResamplingSummary& s) { return "<ResamplingSummary " + s.BriefReport() + ">"; });

  m.def("resample_if_needed", [](const py::object& log_weights, const ResamplingOptions& options,
                                 const py::object& rng) {
          ValidateOptions(options);
          // C++ validates log-weights itself (NaN, +inf, all -inf), naming the entry.
          VectorArg lw = ToVector(log_weights, "log_weights", -1, Finiteness::kAny);
          Eigen::VectorXd out = lw.map;
          std::vector<int> ancestors;
          ResamplingSummary summary = WithStream(rng, [&](RandomStream& stream) {
            return ResampleIfNeeded(out, options, stream, &ancestors);
          });
          return py::make_tuple(ToNumpyIndices(ancestors), ToNumpy(out), summary);
        }, py::arg("log_weights"), py::arg("options") = ResamplingOptions(), py::arg("rng") = 0,
        R"doc(
Adaptive resampling step of a particle filter (paper 000, eq. 14).

Returns ``(ancestors, log_weights, summary)``: ancestors (N,) int64 (identity if no resampling),
the normalised (or reset to uniform) log-weights (N,), and a ResamplingSummary.)doc");
}

void BindCore(py::module_& m) {
  BindRandomStreams(m);
  BindLogWeights(m);
  BindResampling(m);
}

}  // namespace indoorloc::bindings

#include "fdsid/paper.hpp"
#include "fdsid/refine.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <random>
#include <thread>

#include <boost/random/normal_distribution.hpp>

#include "fdsid/error.hpp"
#include "progress.hpp"
#include "numerics/eigen_instances.hpp"
#include "numerics/random.hpp"

namespace fdsid {

namespace {

using numerics::splitmix64;

Eigen::MatrixXd from_strings(int rows, int cols, const std::vector<const char*>& entries) {
  Eigen::MatrixXd M(rows, cols);
  for (int i = 0; i < rows; ++i)
    for (int j = 0; j < cols; ++j) M(i, j) = std::strtod(entries[static_cast<size_t>(i * cols + j)], nullptr);
  return M;
}

double mean(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return v.empty() ? 0.0 : s / static_cast<double>(v.size());
}

double sample_sd(const std::vector<double>& v) {
  if (v.size() < 2) return 0.0;
  const double mu = mean(v);
  double s = 0;
  for (double x : v) s += (x - mu) * (x - mu);
  return std::sqrt(s / static_cast<double>(v.size() - 1));
}

}  // namespace

StateSpace akcay_example_system() {
  StateSpace m;
  m.A = from_strings(4, 4, {"0.8876", "0.4494", "0", "0",  //
                            "-0.4494", "0.7978", "0", "0",  //
                            "0", "0", "-0.6129", "0.0645",  //
                            "0", "0", "-6.4516", "-0.7419"});
  m.B = from_strings(4, 1, {"0.2247", "0.8989", "0.0323", "0.1290"});
  m.C = from_strings(1, 4, {"0.4719", "0.1124", "9.6774", "1.6129"});
  m.D = from_strings(1, 1, {"0.9626"});
  return m;
}

Eigen::VectorXd akcay_noise_variance(int M, double epsilon) {
  Eigen::VectorXd v(M + 1);
  for (int k = 0; k <= M; ++k) v(k) = epsilon * epsilon * std::norm(akcay_noise_filter(std::polar(1.0, M_PI * k / M)));
  return v;
}

cplx akcay_noise_filter(cplx z) {
  return (0.2 * z * z - 0.0904 * z + 0.1839) / (z * z - 1.1111 * z + 0.8520);
}

const NameTable<NoiseVariance>& noise_variance_names() {
  static const NameTable<NoiseVariance> names = {{"unit-complex", NoiseVariance::UnitComplex},
                                                 {"unit-per-component", NoiseVariance::UnitPerComponent}};
  return names;
}

const char* to_string(NoiseVariance v) { return name_of(noise_variance_names(), v); }

std::vector<Table1Row> reproduce_table1(const std::vector<int>& Ms) {
  const StateSpace sys = akcay_example_system();
  std::vector<Table1Row> rows;
  for (int M : Ms) {
    SpectrumData d;
    d.m = 1;
    d.M = M;
    d.S = sample_spectrum(sys, M);
    const Eigen::MatrixXd shat = fourier_coefficients(d, Extension::HermitianPart);
    Table1Row row;
    row.M = M;
    row.vo_sigmas = Eigen::JacobiSVD<Eigen::MatrixXd>(van_overschee_matrix(shat, 1, 9, 8)).singularValues();
    row.akcay_sigmas = Eigen::JacobiSVD<Eigen::MatrixXd>(akcay_matrix(shat, 1, 9, 8)).singularValues();
    rows.push_back(row);
  }
  return rows;
}

SpectrumData akcay_noisy_samples(const Eigen::MatrixXcd& clean, int M, double epsilon, NoiseVariance noise,
                                 std::uint64_t seed) {
  std::mt19937_64 gen(seed);
  std::normal_distribution<double> normal(0.0, noise == NoiseVariance::UnitComplex ? std::sqrt(0.5) : 1.0);
  SpectrumData d;
  d.m = 1;
  d.M = M;
  d.S = clean;
  for (int k = 0; k <= M; ++k) {
    const double re = normal(gen), im = normal(gen);
    d.S(0, k) += epsilon * akcay_noise_filter(std::polar(1.0, M_PI * k / M)) * cplx(re, im);
  }
  return d;
}

void spectrum_errors(const StateSpace& model, const Eigen::MatrixXcd& truth, int M, double& l2, double& linf) {
  const int m = model.outputs();
  double sum = 0;
  linf = 0;
  for (int k = 0; k <= M; ++k) {
    const Eigen::MatrixXcd S = power_spectrum(model, std::polar(1.0, M_PI * k / M));
    const Eigen::MatrixXcd diff = S - Eigen::Map<const Eigen::MatrixXcd>(truth.col(k).data(), m, m);
    const double e = m == 1 ? std::abs(diff(0, 0)) : Eigen::JacobiSVD<Eigen::MatrixXcd>(diff).singularValues()(0);
    sum += e * e;
    linf = std::max(linf, e);
  }
  l2 = std::sqrt(sum / (M + 1));
}

std::vector<Table2Row> reproduce_table2(const Table2Options& o) {
  if (o.realizations < 1) throw Error(ErrorKind::Input, "--realizations", "must be at least 1");
  const StateSpace sys = akcay_example_system();
  std::vector<Table2Row> rows;
  ProgressCounter progress(o.progress, o.realizations * static_cast<int>(o.Ms.size()));
  for (int M : o.Ms) {
    const Eigen::MatrixXcd clean = sample_spectrum(sys, M);
    std::vector<double> l2(o.realizations, NAN), linf(o.realizations, NAN);
    std::vector<char> vo_failed(o.realizations, 0);  // 0 ok, 1 failed at step 6, 2 failed elsewhere
    std::vector<double> vo_l2(o.realizations, NAN);
    std::vector<double> l2_ref(o.realizations, NAN), linf_ref(o.realizations, NAN);
    // Up to the constant E|v|² (2 for unit-per-component), which does not move the optimum.
    const Eigen::VectorXd variance = akcay_noise_variance(M, o.epsilon);
    std::atomic<int> next{0};
    std::vector<std::string> failure(o.realizations);  // Algorithm 1's error per realisation ("" when none)
    std::vector<char> bad_input(o.realizations, 0);     // that error says the settings do not fit the samples
    SpectrumOptions so;
    so.order = o.order;
    so.p = o.p;
    so.r = o.r;
    so.extension = o.extension;
    auto worker = [&]() {
      for (int i = next++; i < o.realizations; i = next++) {
        const std::uint64_t seed = splitmix64(o.seed ^ splitmix64(static_cast<std::uint64_t>(i) * 1000003ULL + M));
        SpectrumData noisy = akcay_noisy_samples(clean, M, o.epsilon, o.noise, seed);
        try {
          const SpectrumResult res = identify_spectrum(noisy, so);
          spectrum_errors(res.model, clean, M, l2[i], linf[i]);
          if (o.refine) {
            noisy.variance = variance;
            try {
              spectrum_errors(refine_spectrum(noisy, res.model).model, clean, M, l2_ref[i], linf_ref[i]);
            } catch (const Error&) {
              l2_ref[i] = linf_ref[i] = NAN;
            }
          }
        } catch (const Error& e) {
          failure[i] = e.what();
          bad_input[i] = e.kind() == ErrorKind::Input || e.kind() == ErrorKind::Dimension;
        }
        if (o.vo_epsilon > 0) {
          SpectrumOptions vo = so;
          vo.method = Method::VanOverschee1997;
          try {
            const SpectrumResult vr = identify_spectrum(akcay_noisy_samples(clean, M, o.vo_epsilon, o.noise, seed), vo);
            double unused;
            spectrum_errors(vr.model, clean, M, vo_l2[i], unused);
          } catch (const Error& e) {
            vo_failed[i] = e.kind() == ErrorKind::Split ? 1 : 2;
          }
        }
        progress.add();
      }
    };
    const int threads = std::max(1, o.threads > 0 ? o.threads : static_cast<int>(std::thread::hardware_concurrency()));
    std::vector<std::thread> pool;
    for (int t = 1; t < threads; ++t) pool.emplace_back(worker);
    worker();
    for (auto& t : pool) t.join();
    // Settings these samples cannot take (p + r > N = 2M): every realisation
    // fails alike, so it is bad input, not a result (a user review: M = 10
    // printed mean L2 0.000e+00 with 3/3 failures, exit 0).
    // The lowest realisation's error, so that the message does not depend on the threads' timing.
    for (int i = 0; i < o.realizations; ++i)
      if (bad_input[i]) throw Error(ErrorKind::Input, "--M " + std::to_string(M), failure[i] + "; give a larger --M");

    Table2Row row;
    row.M = M;
    for (int i = 0; i < o.realizations && row.first_failure.empty(); ++i) row.first_failure = failure[i];
    for (int i = 0; i < o.realizations; ++i) {
      if (std::isnan(l2[i])) {
        ++row.failures;
        continue;
      }
      row.l2_all.push_back(l2[i]);
      row.linf_all.push_back(linf[i]);
      if (!o.refine) continue;
      if (std::isnan(l2_ref[i])) {
        ++row.refine_failures;
        continue;
      }
      row.l2_refined_all.push_back(l2_ref[i]);
      row.linf_refined_all.push_back(linf_ref[i]);
    }
    if (o.refine && !row.l2_refined_all.empty()) {
      row.l2_refined = mean(row.l2_refined_all);
      row.linf_refined = mean(row.linf_refined_all);
      row.l2_refined_sd = sample_sd(row.l2_refined_all);
      row.linf_refined_sd = sample_sd(row.linf_refined_all);
    }
    // No realisation returned a model: no mean (NaN, JSON null), never 0.
    row.l2 = row.l2_all.empty() ? NAN : mean(row.l2_all);
    row.linf = row.linf_all.empty() ? NAN : mean(row.linf_all);
    row.l2_sd = row.l2_all.empty() ? NAN : sample_sd(row.l2_all);
    row.linf_sd = row.linf_all.empty() ? NAN : sample_sd(row.linf_all);
    if (o.vo_epsilon > 0) {
      row.vo_runs = o.realizations;
      row.vo_split_failures = static_cast<int>(std::count(vo_failed.begin(), vo_failed.end(), 1));
      row.vo_failures = row.vo_split_failures + static_cast<int>(std::count(vo_failed.begin(), vo_failed.end(), 2));
      std::vector<double> ok;
      for (double v : vo_l2)
        if (!std::isnan(v)) ok.push_back(v);
      row.vo_l2 = ok.empty() ? NAN : mean(ok);
    }
    rows.push_back(row);
  }
  return rows;
}

// ---------------------------------------------------------------------------
// Pintelon (2002) Section 6.1

StateSpace pintelon_plant() {
  StateSpace m;
  m.A = from_strings(4, 4, {"0.8876", "0.4494", "0", "0",  //
                            "-0.4494", "0.7978", "0", "0",  //
                            "0", "0", "-0.6129", "0.064516",  //
                            "0", "0", "-6.4516", "-0.7419"});
  m.B = from_strings(4, 1, {"0.2247", "0.8989", "0.0323", "0.1290"});
  m.C = from_strings(1, 4, {"0.4719", "0.1124", "9.6774", "1.6129"});
  m.D = from_strings(1, 1, {"0.9626"});
  return m;
}

StateSpace pintelon_noise_model() {
  StateSpace m;
  m.A = from_strings(2, 2, {"0.6296", "0.0741", "-7.4074", "0.4815"});
  m.B = from_strings(2, 1, {"0.037", "0.7407"});
  m.C = from_strings(1, 2, {"1.6300", "0.0740"});
  m.D = from_strings(1, 1, {"0.2"});
  return m;
}

double pintelon_noise_variance(double omega) {
  static const StateSpace h = pintelon_noise_model();
  return std::norm(transfer(h, std::polar(1.0, omega))(0, 0) / h.D(0, 0));
}

namespace {

// Per-block sums of the Monte Carlo: Σ G and Σ |G|² for the three estimates.
struct FigureSums {
  Eigen::VectorXcd s[3];
  Eigen::VectorXd s2[3];
  int runs = 0, failures = 0;
  int first_failed_run = -1;  ///< the lowest-numbered failed run of these sums (-1: none)
  std::string first_failure;  ///< its error
  ErrorKind first_failure_kind = ErrorKind::Numerical;
  explicit FigureSums(int F) {
    for (int e = 0; e < 3; ++e) {
      s[e] = Eigen::VectorXcd::Zero(F);
      s2[e] = Eigen::VectorXd::Zero(F);
    }
  }
};

// The noise-free part of Section 6.1's experiment, the same in every run.
struct FigureSetup {
  StateSpace plant;
  Eigen::VectorXd omega, sigma2;  // ω_k = 2π k/2000 and σ_Y(k)² = |H_0(z_k)|²
  Eigen::VectorXcd G0, U;         // G_0(z_k) and the periodic input U(k)
};

// Purpose: reject options the figure cannot use.
// Fails: Error(Input) for runs < 2, M < 4 (Theorem 2 and the bound of
// Eq. 30), F outside 2 ... 999, or a non-positive input level.
void check_figure_options(const FigureOptions& o) {
  if (o.runs < 2) throw Error(ErrorKind::Input, "--runs", "must be at least 2 (a standard deviation)");
  if (o.M < 4)
    throw Error(ErrorKind::Input, "--M", "M = " + std::to_string(o.M) +
                                            ": B and D of the sample-subspace estimate need M >= 4 (Theorem 2) and "
                                            "the bound sqrt((M-2)/(M-3)) needs M > 3");
  if (o.F < 2 || o.F > 999) throw Error(ErrorKind::Input, "--F", "must be in 2 ... 999 (f_k/f_s = k/2000 < 1/2)");
  if (!(o.input_level > 0) || !std::isfinite(o.input_level))
    throw Error(ErrorKind::Input, "--input-level", "must be positive and finite");
}

// Purpose: the grid f_k/f_s = k/2000, the plant (Eq. 36), the noise variance
// (Eq. 37) and the input U(k) = input_level · e^{jφ_k}, φ_k uniform from the
// seed (a periodic input: the same in every run and experiment).
// References: Pintelon (2002) Section 6.1, Eqs. (36), (37).
FigureSetup figure_setup(const FigureOptions& o) {
  FigureSetup s;
  s.plant = pintelon_plant();
  const int F = o.F;
  s.omega.resize(F);
  s.sigma2.resize(F);
  s.G0.resize(F);
  s.U.resize(F);
  std::mt19937_64 phase_gen(splitmix64(o.seed ^ 0x9e3779b97f4a7c15ULL));
  std::uniform_real_distribution<double> phase(0.0, 2 * M_PI);
  for (int k = 0; k < F; ++k) {
    s.omega(k) = 2 * M_PI * (k + 1) / 2000.0;
    s.sigma2(k) = pintelon_noise_variance(s.omega(k));
    s.G0(k) = transfer(s.plant, std::polar(1.0, s.omega(k)))(0, 0);
    s.U(k) = std::polar(o.input_level, phase(phase_gen));
  }
  return s;
}

// One Monte Carlo run i, added to acc.
//
// Purpose: M experiments Y^[l] = G₀ U + N^[l], N^[l] circular complex normal
// of variance σ² (Re, Im each N(0, σ²/2)), from run i's own generator seeded
// by (seed, i); then (i) the sample-subspace estimate θ̂_S (Ŷ, σ̂²/M,
// Section 4.1), (ii) the subspace estimate θ̂ (Ŷ with the true σ²/M) and
// (iii) β̂(α₀): the true A, C (for n_a = 4) with B, D by Eq. (17). For
// n_a ≠ 4 there is no true α of that order; the θ̂ estimate's A, C stand in
// (the paper's Fig. 2 has no dashed curve).
// U_l, Y_l: work space of M x F one-element vectors.
// Fails: a run whose estimates fail (Error) or are not finite counts as a
// failure in acc; an Error of sample_statistics propagates.
void figure_run(const FigureOptions& o, const FigureSetup& su, int i, std::vector<std::vector<Eigen::VectorXcd>>& U_l,
                std::vector<std::vector<Eigen::VectorXcd>>& Y_l, FigureSums& acc) {
  const int F = o.F;
  std::mt19937_64 gen(splitmix64(o.seed ^ splitmix64(static_cast<std::uint64_t>(i) + 0x51ed2701ULL)));
  // Boost's ziggurat normal, not std::normal_distribution's polar method
  // (log, sqrt and rejection: a sixth of a run's time).
  boost::random::normal_distribution<double> normal(0.0, 1.0);
  for (int l = 0; l < o.M; ++l)
    for (int k = 0; k < F; ++k) {
      const double sd = std::sqrt(su.sigma2(k) / 2);
      const double re = normal(gen), im = normal(gen);
      U_l[l][k](0) = su.U(k);
      Y_l[l][k](0) = su.G0(k) * su.U(k) + sd * cplx(re, im);
    }
  SampleStatistics st = sample_statistics(Domain::Discrete, su.omega, U_l, Y_l);
  try {
    // The sample variances and the same Û, Ŷ with the true σ²/M: one QR of
    // step 1b for both (identify_frf_fixed over noise models).
    std::vector<FrfData> models;
    models.reserve(2);
    models.push_back(st.data);
    models.push_back(std::move(st.data));
    for (int k = 0; k < F; ++k) models[1].variance[k](0, 0) = su.sigma2(k) / o.M;
    const std::vector<FrfResult> both = identify_frf_fixed(models, o.order, o.r, ContinuousMethod::Bilinear, 0,
                                                                DiscreteMethod::Monomial, false);
    const StateSpace& eS = both[0].model;
    const StateSpace& eT = both[1].model;
    const FrfData& known = models[1];
    const StateSpace eK = o.order == su.plant.order() ? fit_input_matrices(known, su.plant.A, su.plant.C)
                                                      : fit_input_matrices(known, eT.A, eT.C);
    Eigen::VectorXcd g[3];
    const StateSpace* est[3] = {&eS, &eT, &eK};
    for (int e = 0; e < 3; ++e) g[e] = frequency_response(*est[e], su.omega, 0, 0);
    for (int e = 0; e < 3; ++e)
      if (!g[e].allFinite()) throw Error(ErrorKind::Numerical, "run", "non-finite estimate");
    for (int e = 0; e < 3; ++e) {
      acc.s[e] += g[e];
      acc.s2[e] += g[e].cwiseAbs2();
    }
    ++acc.runs;
  } catch (const Error& e) {
    // Runs within one block go in increasing order: the first kept is the lowest.
    if (acc.failures++ == 0) {
      acc.first_failed_run = i;
      acc.first_failure = e.what();
      acc.first_failure_kind = e.kind();
    }
  }
}

// The Monte Carlo over o.runs runs.
//
// Purpose: Σ G, Σ |G|² and the run counts over all runs.
// Method: blocks of 50 runs handed to o.threads workers (0: one per core);
// sums are accumulated per block and merged in block order, so the result
// does not depend on the thread count.
FigureSums figure_monte_carlo(const FigureOptions& o, const FigureSetup& su) {
  const int F = o.F;
  constexpr int kBlock = 50;
  const int blocks = (o.runs + kBlock - 1) / kBlock;
  std::vector<FigureSums> sums(blocks, FigureSums(F));
  std::atomic<int> next{0};
  ProgressCounter progress(o.progress, o.runs);
  auto worker = [&]() {
    std::vector<std::vector<Eigen::VectorXcd>> U_l(o.M, std::vector<Eigen::VectorXcd>(F, Eigen::VectorXcd::Zero(1)));
    std::vector<std::vector<Eigen::VectorXcd>> Y_l = U_l;
    for (int b = next++; b < blocks; b = next++) {
      for (int i = b * kBlock; i < std::min(o.runs, (b + 1) * kBlock); ++i) figure_run(o, su, i, U_l, Y_l, sums[b]);
      progress.add(std::min(o.runs, (b + 1) * kBlock) - b * kBlock);
    }
  };
  const int threads = std::max(1, o.threads > 0 ? o.threads : static_cast<int>(std::thread::hardware_concurrency()));
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(worker);
  worker();
  for (auto& t : pool) t.join();
  FigureSums total(F);
  for (const FigureSums& b : sums) {
    for (int e = 0; e < 3; ++e) {
      total.s[e] += b.s[e];
      total.s2[e] += b.s2[e];
    }
    total.runs += b.runs;
    total.failures += b.failures;
    if (total.first_failed_run < 0 && b.first_failed_run >= 0) {  // blocks in order: the lowest run
      total.first_failed_run = b.first_failed_run;
      total.first_failure = b.first_failure;
      total.first_failure_kind = b.first_failure_kind;
    }
  }
  return total;
}

// Purpose: the figure's curves from the sums: means, standard deviations,
// the ratio std(G(θ̂_S)) / std(G(θ̂)), Eq. (28)'s theory curve and Eq. (30)'s
// bound √((M − 2)/(M − 3)).
// Method: sample variance of complex G, (Σ|G|² − R |mean|²) / (R − 1).
// Fails: Error(Numerical) when fewer than 2 runs succeeded.
// References: Pintelon (2002) Eqs. (28), (30), Figs. 1-2.
FigureResult figure_statistics(const FigureOptions& o, const FigureSetup& su, const FigureSums& total) {
  const int F = o.F;
  FigureResult res;
  res.runs = total.runs;
  res.failures = total.failures;
  // Settings the lines cannot take (fewer columns of Z than rows: F < r for
  // this SISO plant) fail every run alike: bad input, not a result.
  if (total.failures > 0 && total.first_failure_kind == ErrorKind::Dimension)
    throw Error(ErrorKind::Input, "--F " + std::to_string(F) + " --r " + std::to_string(o.r),
                total.first_failure + "; give a larger --F or a smaller --r");
  if (total.failures > 0)
    res.first_failure = "run " + std::to_string(total.first_failed_run) + ": " + total.first_failure;
  if (total.runs < 2)
    throw Error(ErrorKind::Numerical, "Monte Carlo",
                "fewer than 2 runs succeeded (" + std::to_string(total.failures) + " failed; the first, " +
                    res.first_failure + ")");
  const double R = total.runs;
  Eigen::VectorXd sd[3];
  Eigen::VectorXcd mean[3];
  for (int e = 0; e < 3; ++e) {
    mean[e] = total.s[e] / R;
    sd[e] = ((total.s2[e] - R * mean[e].cwiseAbs2()) / (R - 1)).cwiseMax(0.0).cwiseSqrt();
  }
  res.frequency = (su.omega / (2 * M_PI)).eval();
  res.std_sample = sd[0];
  res.std_subspace = sd[1];
  res.std_known_alpha = sd[2];
  res.mean_sample = mean[0];
  res.mean_subspace = mean[1];
  res.truth = su.G0;
  res.ratio = sd[0].cwiseQuotient(sd[1]);
  res.theory = (1.0 + sd[2].cwiseAbs2().cwiseQuotient((o.M - 3) * sd[1].cwiseAbs2()).array()).sqrt().matrix();
  res.bound = std::sqrt(double(o.M - 2) / (o.M - 3));
  std::vector<double> r(res.ratio.data(), res.ratio.data() + F);
  std::nth_element(r.begin(), r.begin() + F / 2, r.end());
  res.median_ratio = r[F / 2];
  return res;
}

}  // namespace

FigureResult reproduce_pintelon_figure(const FigureOptions& o) {
  check_figure_options(o);
  const FigureSetup setup = figure_setup(o);
  return figure_statistics(o, setup, figure_monte_carlo(o, setup));
}

}  // namespace fdsid

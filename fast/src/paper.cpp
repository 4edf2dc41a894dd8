#include "fdsid/paper.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <random>
#include <thread>

#include "fdsid/error.hpp"

namespace fdsid {

namespace {

Eigen::MatrixXd from_strings(int rows, int cols, const std::vector<const char*>& entries) {
  Eigen::MatrixXd M(rows, cols);
  for (int i = 0; i < rows; ++i)
    for (int j = 0; j < cols; ++j) M(i, j) = std::strtod(entries[static_cast<size_t>(i * cols + j)], nullptr);
  return M;
}

std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
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

cplx akcay_noise_filter(cplx z) {
  return (0.2 * z * z - 0.0904 * z + 0.1839) / (z * z - 1.1111 * z + 0.8520);
}

const char* to_string(NoiseVariance v) {
  return v == NoiseVariance::UnitComplex ? "unit-complex" : "unit-per-component";
}

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
  for (int M : o.Ms) {
    const Eigen::MatrixXcd clean = sample_spectrum(sys, M);
    std::vector<double> l2(o.realizations, NAN), linf(o.realizations, NAN);
    std::vector<char> vo_failed(o.realizations, 0);  // 0 ok, 1 failed at step 6, 2 failed elsewhere
    std::vector<double> vo_l2(o.realizations, NAN);
    std::atomic<int> next{0};
    SpectrumOptions so;
    so.order = o.order;
    so.p = o.p;
    so.r = o.r;
    so.extension = o.extension;
    auto worker = [&]() {
      for (int i = next++; i < o.realizations; i = next++) {
        const std::uint64_t seed = splitmix64(o.seed ^ splitmix64(static_cast<std::uint64_t>(i) * 1000003ULL + M));
        try {
          const SpectrumResult res =
              identify_spectrum(akcay_noisy_samples(clean, M, o.epsilon, o.noise, seed), so);
          spectrum_errors(res.model, clean, M, l2[i], linf[i]);
        } catch (const Error&) {
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
      }
    };
    const int threads = std::max(1, o.threads > 0 ? o.threads : static_cast<int>(std::thread::hardware_concurrency()));
    std::vector<std::thread> pool;
    for (int t = 1; t < threads; ++t) pool.emplace_back(worker);
    worker();
    for (auto& t : pool) t.join();

    Table2Row row;
    row.M = M;
    for (int i = 0; i < o.realizations; ++i) {
      if (std::isnan(l2[i])) {
        ++row.failures;
        continue;
      }
      row.l2_all.push_back(l2[i]);
      row.linf_all.push_back(linf[i]);
    }
    row.l2 = mean(row.l2_all);
    row.linf = mean(row.linf_all);
    row.l2_sd = sample_sd(row.l2_all);
    row.linf_sd = sample_sd(row.linf_all);
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

}  // namespace fdsid

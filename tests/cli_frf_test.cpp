// Command-line tests of fdsid identify-frf, simulate-records and reproduce
// fig1/fig2 (Pintelon 2002). Same harness as cli_test.cpp (run_fdsid forks and
// execs FDSID_EXE with a time limit; IsBadInput checks exit status 2 and one
// stderr line "fdsid: ..." naming the problem). Input files are written at test
// time into a fresh temporary folder that the fixture removes afterwards.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <complex>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <initializer_list>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "linalg.hpp"
#include "cli_harness.hpp"
#include "gap_systems.hpp"

#include <Eigen/Dense>

#include "fdsid/frf_id.hpp"
#include "fdsid/io.hpp"
#include "fdsid/model.hpp"

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

using namespace fdsid::cli_harness;



/// Replaces line number `lineno` (1-based, header = line 1) of text.
std::string replace_line(const std::string& text, int lineno, const std::string& replacement) {
  std::istringstream in(text);
  std::string line, out;
  for (int i = 1; std::getline(in, line); ++i) out += (i == lineno ? replacement : line) + "\n";
  return out;
}

// ---------------------------------------------------------------------------
// Systems and files

constexpr double kU = 0x1p-53;  // unit roundoff of double

/// Pintelon (2002) Eq. (36) plant (McKelvey et al. 1996) as decimal strings.
const char* kPintelonModel = R"({"domain": "discrete", "sample_time": 1.0,
  "A": [["0.8876", "0.4494", "0", "0"], ["-0.4494", "0.7978", "0", "0"],
        ["0", "0", "-0.6129", "0.064516"], ["0", "0", "-6.4516", "-0.7419"]],
  "B": [["0.2247"], ["0.8989"], ["0.0323"], ["0.1290"]],
  "C": [["0.4719", "0.1124", "9.6774", "1.6129"]],
  "D": [["0.9626"]]})";

fdsid::StateSpace pintelon_plant() {
  fdsid::StateSpace s;
  s.A.resize(4, 4);
  s.A << 0.8876, 0.4494, 0, 0, -0.4494, 0.7978, 0, 0, 0, 0, -0.6129, 0.064516, 0, 0, -6.4516, -0.7419;
  s.B.resize(4, 1);
  s.B << 0.2247, 0.8989, 0.0323, 0.1290;
  s.C.resize(1, 4);
  s.C << 0.4719, 0.1124, 9.6774, 1.6129;
  s.D = Eigen::MatrixXd::Constant(1, 1, 0.9626);
  return s;
}

/// A continuous fourth-order plant (rad/s): two lightly damped modes,
/// ω₀ = 1 (ζ = 0.1) and ω₀ = 10 (ζ = 0.3); poles −0.1 ± 0.995j, −3 ± 9.54j.
fdsid::StateSpace continuous_plant() {
  fdsid::StateSpace s;
  s.domain = fdsid::Domain::Continuous;
  s.sample_time = 0;
  s.A.resize(4, 4);
  s.A << 0, 1, 0, 0, -1, -0.2, 0, 0, 0, 0, 0, 1, 0, 0, -100, -6;
  s.B.resize(4, 1);
  s.B << 0, 1, 0, 1;
  s.C.resize(1, 4);
  s.C << 1, 0.5, 100, 2;
  s.D = Eigen::MatrixXd::Constant(1, 1, 0.1);
  return s;
}

std::complex<double> G_at(const fdsid::StateSpace& s, std::complex<double> xi) {
  const Eigen::Index n = s.A.rows();
  const Eigen::MatrixXcd R = fdsid::testing::inverse(Eigen::MatrixXcd(xi * Eigen::MatrixXcd::Identity(n, n) - s.A.cast<std::complex<double>>()));
  return (s.C.cast<std::complex<double>>() * R * s.B.cast<std::complex<double>>())(0, 0) + s.D(0, 0);
}

/// Eigenvalue condition of A: κ₂(V) of its eigenvector matrix (the Bauer–Fike
/// amplification of a perturbation of A into its eigenvalues).
double eigen_condition(const Eigen::MatrixXd& A) {
  const Eigen::VectorXd s = fdsid::testing::singular_values(fdsid::testing::eigen_decomposition(A).vectors);
  return s(0) / s(s.size() - 1);
}

/// Largest distance from a true pole to the nearest identified pole in the JSON
/// (numbers, or decimal strings with --precision high).
double pole_distance(const Eigen::MatrixXd& A_true, const json& poles) {
  const Eigen::VectorXcd truth = fdsid::testing::eigenvalues(A_true);
  auto num = [](const json& v) { return v.is_string() ? std::stod(v.get<std::string>()) : v.get<double>(); };
  double worst = 0;
  for (Eigen::Index i = 0; i < truth.size(); ++i) {
    double best = INFINITY;
    for (const auto& p : poles) best = std::min(best, std::abs(std::complex<double>(num(p[0]), num(p[1])) - truth(i)));
    worst = std::max(worst, best);
  }
  return worst;
}

/// Significant digits of a decimal string ("-1.2345e-3" → 5).
int significant_digits(const std::string& s) {
  std::string mant = s.substr(0, s.find_first_of("eE"));
  std::string digits;
  for (char ch : mant)
    if (std::isdigit(static_cast<unsigned char>(ch))) digits += ch;
  const size_t first = digits.find_first_not_of('0');
  return first == std::string::npos ? 0 : static_cast<int>(digits.size() - first);
}

std::string frf_csv(const fdsid::StateSpace& s, const std::vector<double>& omega, double var) {
  std::string text = "omega,G_re,G_im,G_var\n";
  char line[160];
  for (double w : omega) {
    const std::complex<double> xi =
        s.domain == fdsid::Domain::Discrete ? std::polar(1.0, w) : std::complex<double>(0.0, w);
    const auto g = G_at(s, xi);
    std::snprintf(line, sizeof line, "%.17g,%.17g,%.17g,%.17g\n", w, g.real(), g.imag(), var);
    text += line;
  }
  return text;
}

class CliFrf : public ::testing::Test {
 protected:
  void SetUp() override {
    static std::atomic<int> counter{0};
    std::random_device rd;
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() / ("fdsid-clifrf-" + std::string(info->name()) + "-" +
                                        std::to_string(getpid()) + "-" + std::to_string(counter++) + "-" +
                                        std::to_string(rd()));
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  std::string write(const std::string& name, const std::string& text) {
    const fs::path p = dir_ / name;
    std::ofstream(p, std::ios::binary) << text;
    return p.string();
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  json read_json(const std::string& name) {
    std::ifstream f(path(name));
    return json::parse(f);
  }

  /// simulate-records on the Pintelon plant: P samples per period, M periods,
  /// lines 1, 3, ..., P/2 − 1, white output noise of std `noise`.
  void simulate(int P, int M, double noise, const std::string& stem, int seed = 7) {
    const std::string model = write("plant.json", kPintelonModel);
    std::vector<std::string> args = {"simulate-records", "--model", model, "--out", path(stem + ".csv"),
                                     "--meta-out", path(stem + ".meta.json"), "--period", std::to_string(P),
                                     "--periods", std::to_string(M), "--seed", std::to_string(seed), "--lines"};
    for (int k = 1; k <= P / 2 - 1; k += 2) args.push_back(std::to_string(k));
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.17g", noise);
    args.insert(args.end(), {"--noise-std", buf});
    ASSERT_TRUE(Succeeded(run_fdsid(args)));
  }

  /// A 3-row FRF file of the Pintelon plant whose row 2 (file line 3) is `row`.
  std::string frf_with_row(const std::string& name, const std::string& row) {
    std::string text = frf_csv(pintelon_plant(), {0.5, 1.0, 1.5}, 1e-6);
    return write(name, replace_line(text, 3, row));
  }

  fs::path dir_;
};

void expect_contract_fields(const json& j, const std::string& domain, const std::string& method) {
  for (const char* key : {"A", "B", "C", "D", "domain", "sample_time", "order", "method", "singular_values", "poles"})
    EXPECT_TRUE(j.contains(key)) << "missing \"" << key << "\" in " << j.dump().substr(0, 400);
  EXPECT_EQ(j["domain"], domain);
  EXPECT_EQ(j["method"], method);
  EXPECT_EQ(j["order"], 4);
  ASSERT_EQ(j["A"].size(), 4u);
  for (const auto& row : j["A"]) EXPECT_EQ(row.size(), 4u);
  ASSERT_EQ(j["B"].size(), 4u);
  EXPECT_EQ(j["B"][0].size(), 1u);
  ASSERT_EQ(j["C"].size(), 1u);
  EXPECT_EQ(j["C"][0].size(), 4u);
  ASSERT_EQ(j["D"].size(), 1u);
  EXPECT_EQ(j["poles"].size(), 4u);
  EXPECT_GE(j["singular_values"].size(), 5u);  // r p = 8 ≥ n + 1: the gap after σ_4 is visible
}

// ---------------------------------------------------------------------------
// Periodic records → identify-frf

// Pole tolerance for noisy records (first-order perturbation, stated constants):
// output noise of std σ_n per sample is, under the 1/√P DFT of Eq. (4), noise of
// E|N(k)|² = σ_n² per period at each excited line, σ_n²/M after the mean over M
// periods. |U(k)| = rms √(P / (2L)) for an RMS-1 multisine on L lines. The
// largest of 2F real Gaussian components is below 5 standard deviations (tail
// e^{−12.5}·2F ≈ 2e-4 for F = 32), so the relative data error is
// ε_data ≤ 5 σ_n / (√M |U| min_k |G(e^{jω_k})|). The diagnostics' κ (first-order
// amplification of relative data errors into Â) and the Bauer–Fike factor
// κ₂(V) of the true A map it to the poles: |δλ| ≤ c κ κ₂(V) ‖A‖₂ ε_data with
// c = 10 for the second-order terms and the norm-equivalence factors (n = 4).
TEST_F(CliFrf, SimulatedRecordsIdentifyThePlant) {
  const int P = 128, M = 8, L = 32;
  const double noise = 1e-6;
  simulate(P, M, noise, "rec");
  const RunResult r = run_fdsid({"identify-frf", "--data", path("rec.csv"), "--meta", path("rec.meta.json"),
                                 "--order", "4", "--r", "8", "--json", path("out.json")});
  ASSERT_TRUE(Succeeded(r));
  const json j = read_json("out.json");
  expect_contract_fields(j, "discrete", "pintelon2002-alg1");
  EXPECT_EQ(j["sample_time"], 1.0);

  const fdsid::StateSpace plant = pintelon_plant();
  double gmin = INFINITY;
  for (int k = 1; k < P / 2; k += 2) gmin = std::min(gmin, std::abs(G_at(plant, std::polar(1.0, 2 * M_PI * k / P))));
  const double U = std::sqrt(P / (2.0 * L));
  const double eps_data = 5 * noise / (std::sqrt(double(M)) * U * gmin);
  const double kappa = j["diagnostics"]["condition"].get<double>();
  const double tol = 10 * kappa * eigen_condition(plant.A) * plant.A.operatorNorm() * eps_data;
  const double err = pole_distance(plant.A, j["poles"]);
  EXPECT_LE(err, tol) << "kappa " << kappa << ", eps_data " << eps_data;
  std::printf("records: pole error %.3g, tolerance %.3g (kappa %.3g, eps_data %.3g)\n", err, tol, kappa, eps_data);
}

// --precision high: the 50-digit reference on the same records; every number a
// decimal string of ≥ 30 significant digits; poles within the same noise
// tolerance as above (the estimator is the same, rounding is negligible).
TEST_F(CliFrf, SimulatedRecordsHighPrecision) {
  const int P = 64, M = 6, L = 16;
  const double noise = 1e-6;
  simulate(P, M, noise, "rec");
  const RunResult r = run_fdsid({"identify-frf", "--data", path("rec.csv"), "--meta", path("rec.meta.json"),
                                 "--order", "4", "--r", "8", "--precision", "high", "--json", path("out.json")},
                                600);
  ASSERT_TRUE(Succeeded(r));
  const json j = read_json("out.json");
  expect_contract_fields(j, "discrete", j["method"].get<std::string>());
  for (const char* key : {"A", "B", "C", "D", "poles"})
    for (const auto& row : j[key])
      for (const auto& v : row) {
        ASSERT_TRUE(v.is_string()) << key << " entry " << v.dump() << " is not a decimal string";
        const std::string s = v.get<std::string>();
        // An exact zero (e.g. the imaginary part of a real pole) has no significant digits to carry.
        if (std::stod(s) != 0.0) {
          EXPECT_GE(significant_digits(s), 30) << key << " entry " << s;
        }
      }
  const fdsid::StateSpace plant = pintelon_plant();
  double gmin = INFINITY;
  for (int k = 1; k < P / 2; k += 2) gmin = std::min(gmin, std::abs(G_at(plant, std::polar(1.0, 2 * M_PI * k / P))));
  const double eps_data = 5 * noise / (std::sqrt(double(M)) * std::sqrt(P / (2.0 * L)) * gmin);
  // κ of the same data from the double-precision run.
  ASSERT_TRUE(Succeeded(run_fdsid({"identify-frf", "--data", path("rec.csv"), "--meta", path("rec.meta.json"),
                                   "--order", "4", "--r", "8", "--json", path("double.json")})));
  const double kappa = read_json("double.json")["diagnostics"]["condition"].get<double>();
  const double tol = 10 * kappa * eigen_condition(plant.A) * plant.A.operatorNorm() * eps_data;
  const double err = pole_distance(plant.A, j["poles"]);
  EXPECT_LE(err, tol);
  std::printf("records (high): pole error %.3g, tolerance %.3g\n", err, tol);
}

// ---------------------------------------------------------------------------
// FRF files → identify-frf
//
// Noise-free FRF (only the %.17g rounding of the CSV, relative u): the estimate
// is exact up to rounding, and the diagnostics' error_estimate = u κ bounds the
// relative error of Â; Bauer–Fike gives |δλ| ≤ c · error_estimate · κ₂(V) ‖A‖₂
// with c = 100 (the CSV rounding, the %.17g JSON output and O(n) rounding in
// the eigenvalue solve, each a few u relative, for n = 4).
void expect_exact_poles(const fdsid::StateSpace& plant, const json& j) {
  const double est = j["diagnostics"]["error_estimate"].get<double>();
  ASSERT_GT(est, 0);
  EXPECT_GE(est, kU);
  const double tol = 100 * est * eigen_condition(plant.A) * plant.A.operatorNorm();
  const double err = pole_distance(plant.A, j["poles"]);
  EXPECT_LE(err, tol) << "error_estimate " << est;
  std::printf("frf: pole error %.3g, tolerance %.3g (error_estimate %.3g)\n", err, tol, est);
}

TEST_F(CliFrf, DiscreteFrfFile) {
  std::vector<double> omega;
  for (int k = 0; k < 80; ++k) omega.push_back(M_PI * (k + 0.5) / 80);
  const std::string f = write("g.csv", frf_csv(pintelon_plant(), omega, 1e-8));
  const RunResult r = run_fdsid({"identify-frf", "--frf", f, "--order", "4", "--r", "8", "--json", path("out.json")});
  ASSERT_TRUE(Succeeded(r));
  const json j = read_json("out.json");
  expect_contract_fields(j, "discrete", "pintelon2002-alg1");
  expect_exact_poles(pintelon_plant(), j);
}

TEST_F(CliFrf, ContinuousFrfBilinearAndOrthogonal) {
  std::vector<double> omega;
  for (int k = 0; k < 60; ++k) omega.push_back(0.1 * std::pow(1000.0, k / 59.0));  // 0.1 … 100 rad/s
  const fdsid::StateSpace plant = continuous_plant();
  const std::string f = write("g.csv", frf_csv(plant, omega, 1e-8));
  for (const std::string method : {"bilinear", "orthogonal"}) {
    SCOPED_TRACE(method);
    const std::string out = path(method + ".json");
    const RunResult r = run_fdsid({"identify-frf", "--frf", f, "--domain", "continuous", "--method", method,
                                   "--order", "4", "--r", "8", "--json", out});
    ASSERT_TRUE(Succeeded(r));
    const json j = read_json(method + ".json");
    expect_contract_fields(j, "continuous", "pintelon2002-alg2-" + method);
    expect_exact_poles(plant, j);
    // Review: a continuous-time model from an FRF in rad/s has no sample
    // period: 0, as the 50-digit reference writes it (it said 1.0, "sampled at 1 s").
    EXPECT_EQ(j["sample_time"].get<double>(), 0.0);
  }
  const std::string high = path("high.json");
  ASSERT_TRUE(Succeeded(run_fdsid({"identify-frf", "--frf", f, "--domain", "continuous", "--order", "4", "--r", "8",
                                   "--precision", "high", "--json", high}, 600)));
  EXPECT_EQ(std::stod(read_json("high.json")["sample_time"].get<std::string>()), 0.0);
}

// ---------------------------------------------------------------------------
// Bad input: exit 2, one stderr line naming the problem

TEST_F(CliFrf, TooFewPeriods) {
  simulate(16, 3, 1e-3, "rec");
  EXPECT_TRUE(IsBadInput(run_fdsid({"identify-frf", "--data", path("rec.csv"), "--meta", path("rec.meta.json"),
                                    "--order", "2"}),
                         {"periods", "M >= 4"}));
}

TEST_F(CliFrf, RecordNotWholePeriods) {
  simulate(16, 5, 1e-3, "rec");
  std::ifstream in(path("rec.csv"));
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  text.erase(text.rfind('\n', text.size() - 2) + 1);  // drop the last sample
  const std::string f = write("short.csv", text);
  EXPECT_TRUE(IsBadInput(run_fdsid({"identify-frf", "--data", f, "--meta", path("rec.meta.json"), "--order", "2"}),
                         {"79 samples", "whole periods"}));
}

TEST_F(CliFrf, NoExcitedLines) {
  simulate(16, 5, 1e-3, "rec");
  const std::string meta = write("m.json", R"({"period": 16, "periods": 5, "sample_time": 1, "excited_lines": []})");
  EXPECT_TRUE(IsBadInput(run_fdsid({"identify-frf", "--data", path("rec.csv"), "--meta", meta, "--order", "2"}),
                         {meta, "excited_lines", "no excited lines"}));
}

TEST_F(CliFrf, ExcitedLineAboveHalfPeriod) {
  simulate(16, 5, 1e-3, "rec");
  const std::string meta = write("m.json", R"({"period": 16, "periods": 5, "sample_time": 1, "excited_lines": [1, 3, 9]})");
  EXPECT_TRUE(IsBadInput(run_fdsid({"identify-frf", "--data", path("rec.csv"), "--meta", meta, "--order", "2"}),
                         {meta, "excited_lines", "line 9", "P/2 = 8"}));
}

TEST_F(CliFrf, ZeroOrNegativeVariance) {
  for (const std::string v : {"0", "-1e-3"}) {
    const std::string f = frf_with_row("var" + v + ".csv", "1,0.5,0.25," + v);
    EXPECT_TRUE(IsBadInput(run_fdsid({"identify-frf", "--frf", f, "--order", "1"}), {f, "line 3", "G_var", "positive"}));
  }
}

TEST_F(CliFrf, RepeatedFrequency) {
  const std::string f = frf_with_row("rep.csv", "0.5,0.5,0.25,1e-6");
  // Row 2 (file line 3) repeats row 1 (file line 2): both file lines named.
  EXPECT_TRUE(IsBadInput(run_fdsid({"identify-frf", "--frf", f, "--order", "1"}),
                         {f + " line 3 column omega", "repeats " + f + " line 2"}));
  // Out of order, two repeated frequencies and a blank line: the first repeat
  // in file order is named (line 6 repeats line 3; line 7 repeats line 2),
  // with file lines, not row numbers.
  const std::string g = write("rep2.csv", "omega,G_re,G_im,G_var\n0.3,1,0,1e-6\n0.1,1,0,1e-6\n\n0.2,1,0,1e-6\n"
                                          "0.1,1,0,1e-6\n0.3,1,0,1e-6\n0.4,1,0,1e-6\n");
  EXPECT_TRUE(IsBadInput(run_fdsid({"identify-frf", "--frf", g, "--order", "1"}),
                         {g + " line 6 column omega", "omega = 0.1", "repeats " + g + " line 3"}));
}

TEST_F(CliFrf, DiscreteOmegaAbovePi) {
  const std::string f = frf_with_row("pi.csv", "3.2,0.5,0.25,1e-6");
  EXPECT_TRUE(IsBadInput(run_fdsid({"identify-frf", "--frf", f, "--order", "1"}),
                         {f + " line 3", "3.2", "outside [0, pi]", "--domain continuous"}));
}

TEST_F(CliFrf, ContinuousOmegaNotPositive) {
  for (const std::string w : {"0", "-1"}) {
    const std::string f = frf_with_row("w" + w + ".csv", w + ",0.5,0.25,1e-6");
    EXPECT_TRUE(IsBadInput(run_fdsid({"identify-frf", "--frf", f, "--domain", "continuous", "--order", "1"}),
                           {f, "positive for continuous time"}));
  }
}

TEST_F(CliFrf, MissingFiles) {
  const std::string missing = path("missing.csv");
  EXPECT_TRUE(IsBadInput(run_fdsid({"identify-frf", "--frf", missing, "--order", "1"}), {missing, "cannot open"}));
  simulate(16, 5, 1e-3, "rec");
  EXPECT_TRUE(IsBadInput(run_fdsid({"identify-frf", "--data", missing, "--meta", path("rec.meta.json")}),
                         {missing, "cannot open"}));
  const std::string missing_meta = path("missing.json");
  EXPECT_TRUE(IsBadInput(run_fdsid({"identify-frf", "--data", path("rec.csv"), "--meta", missing_meta}),
                         {missing_meta, "cannot open"}));
}

TEST_F(CliFrf, MalformedMetaJson) {
  simulate(16, 5, 1e-3, "rec");
  const std::string meta = write("bad.json", "{\"period\": 16, \"periods\": 5,\n \"excited_lines\": [1, 3\n}\n");
  EXPECT_TRUE(IsBadInput(run_fdsid({"identify-frf", "--data", path("rec.csv"), "--meta", meta}),
                         {meta, "malformed JSON"}));
}

TEST_F(CliFrf, BothOrNeitherSource) {
  simulate(16, 5, 1e-3, "rec");
  const std::string f = write("g.csv", frf_csv(pintelon_plant(), {0.5, 1.0, 1.5}, 1e-6));
  EXPECT_TRUE(IsBadInput(run_fdsid({"identify-frf", "--frf", f, "--data", path("rec.csv"), "--meta",
                                    path("rec.meta.json")}),
                         {"--frf", "--data"}));
  EXPECT_TRUE(IsBadInput(run_fdsid({"identify-frf", "--order", "1"}), {"--frf", "--data"}));
}

TEST_F(CliFrf, RNotAboveOrder) {
  std::vector<double> omega;
  for (int k = 0; k < 40; ++k) omega.push_back(M_PI * (k + 0.5) / 40);
  const std::string f = write("g.csv", frf_csv(pintelon_plant(), omega, 1e-8));
  for (const std::string r : {"4", "3"})
    EXPECT_TRUE(IsBadInput(run_fdsid({"identify-frf", "--frf", f, "--order", "4", "--r", r}),
                           {"r = " + r, "must exceed the order"}));
}

// Issue "nothing lost": an output that names an input is refused before
// anything is read or written, and the input is left byte for byte as it was.
TEST_F(CliFrf, OutputEqualToInputIsRefused) {
  std::vector<double> omega;
  for (int k = 0; k < 40; ++k) omega.push_back(M_PI * (k + 0.5) / 40);
  const std::string text = frf_csv(pintelon_plant(), omega, 1e-8);
  const std::string f = write("g.csv", text);
  EXPECT_TRUE(IsBadInput(run_fdsid({"identify-frf", "--frf", f, "--order", "4", "--json", f}),
                         {"--json", "refusing to overwrite"}));
  // The same file through another spelling of its path.
  EXPECT_TRUE(IsBadInput(run_fdsid({"identify-frf", "--frf", f, "--order", "4", "--json", path("./g.csv")}),
                         {"refusing to overwrite"}));
  std::ifstream in(f);
  const std::string after((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(after, text);
}

// Resource limits: an r whose step 1 would not finish is refused with the figure.
TEST_F(CliFrf, OversizedRIsRefusedBeforeAllocation) {
  std::vector<double> omega;
  for (int k = 0; k < 40; ++k) omega.push_back(M_PI * (k + 0.5) / 40);
  const std::string f = write("g.csv", frf_csv(pintelon_plant(), omega, 1e-8));
  EXPECT_TRUE(IsBadInput(run_fdsid({"identify-frf", "--frf", f, "--order", "4", "--r", "100000"}),
                         {"r (m + p) = 200000", "exceeds the supported 4000"}));
}

TEST_F(CliFrf, NanInCsv) {
  const std::string f = frf_with_row("nan.csv", "1,nan,0.25,1e-6");
  EXPECT_TRUE(IsBadInput(run_fdsid({"identify-frf", "--frf", f, "--order", "1"}), {f, "line 3", "G_re", "not finite"}));
  const std::string g = frf_with_row("nanvar.csv", "1,0.5,0.25,NaN");
  EXPECT_TRUE(IsBadInput(run_fdsid({"identify-frf", "--frf", g, "--order", "1"}), {g, "line 3", "G_var"}));
}

// ---------------------------------------------------------------------------
// reproduce fig1 / fig2

TEST_F(CliFrf, ReproduceFiguresJsonToStdout) {
  for (const std::string fig : {"fig1", "fig2"}) {
    SCOPED_TRACE(fig);
    const RunResult r = run_fdsid({"reproduce", fig, "--runs", "50", "--json", "-"}, 300);
    ASSERT_TRUE(Succeeded(r));
    json j;
    ASSERT_NO_THROW(j = json::parse(r.out)) << "stdout is not JSON only: " << r.out.substr(0, 300);
    ASSERT_TRUE(j.contains("frequency") && j.contains("ratio") && j.contains("bound"));
    EXPECT_EQ(j["frequency"].size(), 999u);
    EXPECT_EQ(j["ratio"].size(), 999u);
    EXPECT_DOUBLE_EQ(j["frequency"][0].get<double>(), 1.0 / 2000);
    EXPECT_DOUBLE_EQ(j["frequency"][998].get<double>(), 999.0 / 2000);
    // Eq. (30) with M = 7: √(5/4), to the rounding of one sqrt and one division (2u).
    EXPECT_NEAR(j["bound"].get<double>(), std::sqrt(5.0 / 4.0), 2 * kU * std::sqrt(5.0 / 4.0));
    EXPECT_EQ(j["M"], 7);
    EXPECT_EQ(j["order"], fig == "fig1" ? 4 : 1);
    for (const auto& v : j["ratio"]) EXPECT_GT(v.get<double>(), 0);
  }
}

// ---------------------------------------------------------------------------
// gap and gap-validate (CONTRACTS.md "fdsid gap report")

// The plant with its output one sample late: G'(z) = z⁻¹ G(z).
std::string delayed_plant_json() { return fdsid::model_to_json(fdsid::testing::one_sample_delay(pintelon_plant())).dump(); }

void expect_gap_fields(const json& j) {
  for (const char* key : {"gap_before", "gap_after", "present", "bands", "candidates"})
    EXPECT_TRUE(j.contains(key)) << "missing \"" << key << "\"";
  ASSERT_EQ(j["candidates"].size(), 7u);  // every effect of the contracts' table
  std::vector<std::string> names;
  for (const auto& c : j["candidates"]) {
    for (const char* key : {"effect", "gap_after", "shrink", "parameters"}) EXPECT_TRUE(c.contains(key));
    names.push_back(c["effect"]);
    // shrink = 1 − gap_after/gap_before (contracts), to rounding of the printed doubles
    EXPECT_NEAR(c["shrink"].get<double>(), 1 - c["gap_after"].get<double>() / j["gap_before"].get<double>(), 1e-12);
  }
  std::sort(names.begin(), names.end());
  EXPECT_EQ(names, (std::vector<std::string>{"delay", "gain_error", "leakage", "mode_mismatch", "nonlinearity",
                                             "sensor_dynamics", "unmodelled_mode"}));
  for (size_t i = 1; i < j["candidates"].size(); ++i)  // best first
    EXPECT_LE(j["candidates"][i - 1]["gap_after"].get<double>(), j["candidates"][i]["gap_after"].get<double>());
  // the equal-noise-power decision is the one its p and effect_alpha give
  // (a single-output report's tests; a two-output report's are per channel)
  if (j.contains("channels")) return;
  ASSERT_TRUE(j.contains("tests"));
  const json& t = j.at("tests");
  EXPECT_EQ(t.at("period_power_unequal").get<bool>(),
            t.at("p_period_power").get<double>() < t.at("effect_alpha").get<double>());
}

TEST_F(CliFrf, GapOfTheRightModelIsNoiseAlone) {
  // P = 256, lines 1, 3, …, 127 (K = 64), M = 8: the gap of a right model has
  // mean 1 and sd √(var F(2,14))/μ/√K = 0.15 (gap.hpp); 1.75 is 5 sd. The
  // verdict is empty unless one of three tests at 1 % fires (seed fixed).
  simulate(256, 8, 0.01, "rec");
  const std::string model = write("model.json", kPintelonModel);
  const RunResult r = run_fdsid({"gap", "--model", model, "--data", path("rec.csv"), "--meta", path("rec.meta.json"),
                                 "--json", path("gap.json"), "--table", path("gap.csv")});
  ASSERT_TRUE(Succeeded(r));
  const json j = read_json("gap.json");
  expect_gap_fields(j);
  EXPECT_LT(j["gap_before"].get<double>(), 1.75);
  EXPECT_TRUE(j["present"].empty()) << j.dump(1);
  EXPECT_EQ(j["gap_after"], j["gap_before"]);
  std::ifstream t(path("gap.csv"));
  std::string header, line;
  std::getline(t, header);
  EXPECT_EQ(header, "frequency_hz,t_before,t_after,flagged");
  int rows = 0;
  while (std::getline(t, line)) rows += !line.empty();
  EXPECT_EQ(rows, 64);  // one row per excited line: 1, 3, …, 127
}

TEST_F(CliFrf, GapFindsADelayAndPrintsTheVerdict) {
  const std::string truth = write("truth.json", delayed_plant_json());
  std::vector<std::string> args = {"simulate-records", "--model", truth, "--out", path("rec.csv"), "--meta-out",
                                   path("rec.meta.json"), "--period", "256", "--periods", "8", "--noise-std",
                                   "0.01", "--lines"};
  for (int k = 1; k < 128; k += 2) args.push_back(std::to_string(k));
  ASSERT_TRUE(Succeeded(run_fdsid(args)));
  const std::string model = write("model.json", kPintelonModel);
  const RunResult r =
      run_fdsid({"gap", "--model", model, "--data", path("rec.csv"), "--meta", path("rec.meta.json"), "--json", "-"});
  ASSERT_TRUE(Succeeded(r));
  const json j = json::parse(r.out);
  expect_gap_fields(j);
  EXPECT_EQ(j["present"], json::array({"delay"}));
  EXPECT_LT(j["gap_after"].get<double>(), 2.0);
  EXPECT_GT(j["gap_before"].get<double>(), 100.0);
  // the human report names the verdict
  const RunResult h = run_fdsid({"gap", "--model", model, "--data", path("rec.csv"), "--meta", path("rec.meta.json")});
  ASSERT_TRUE(Succeeded(h));
  EXPECT_NE(h.out.find("verdict: delay"), std::string::npos) << h.out;
  // Review finding 21: p-values that underflowed printed as 0.000e+00, flags
  // and orders as 2.0000e+00.
  if (j["tests"]["p_gap"].get<double>() < 1e-300) {
    EXPECT_NE(h.out.find("p(gap) < 1e-300"), std::string::npos) << h.out;
  }
  EXPECT_EQ(h.out.find("0.000e+00"), std::string::npos) << h.out;
  EXPECT_EQ(h.out.find(" 0.00e+00"), std::string::npos) << h.out;
  EXPECT_EQ(h.out.find("=1.0000e+00"), std::string::npos) << h.out;
  EXPECT_EQ(h.out.find("=0.0000e+00"), std::string::npos) << h.out;
}

TEST_F(CliFrf, GapRefusesWhatItCannotUse) {
  simulate(256, 8, 0.01, "rec");
  simulate(256, 8, 0.0, "clean");
  const std::string model = write("model.json", kPintelonModel);
  EXPECT_TRUE(IsBadInput(run_fdsid({"gap", "--model", model, "--data", path("clean.csv"), "--meta",
                                    path("clean.meta.json")}),
                         {"do not vary"}));
  EXPECT_TRUE(IsBadInput(run_fdsid({"gap", "--model", path("missing.json"), "--data", path("rec.csv"), "--meta",
                                    path("rec.meta.json")}),
                         {"missing.json"}));
  json meta = read_json("rec.meta.json");
  meta["periods"] = 3;
  meta["period"] = 256 * 8 / 3 + 1;
  const std::string short_meta = write("short.meta.json", meta.dump());
  EXPECT_TRUE(IsBadInput(
      run_fdsid({"gap", "--model", model, "--data", path("rec.csv"), "--meta", short_meta}), {}));
  const std::string mimo = write("mimo.json", R"({"domain": "discrete", "sample_time": 1.0, "A": [[0.5]], "B": [[1]],
      "C": [[1], [2]], "D": [[0], [0]]})");
  EXPECT_TRUE(IsBadInput(run_fdsid({"gap", "--model", mimo, "--data", path("rec.csv"), "--meta", path("rec.meta.json")}),
                         {"2 outputs", "the record 1"}));
  EXPECT_TRUE(IsBadInput(run_fdsid({"gap", "--model", model, "--data", path("rec.csv"), "--meta", path("rec.meta.json"),
                                    "--alpha", "5"}),
                         {"--alpha", "(0, 1)"}));
  json half = json::parse(kPintelonModel);
  half["sample_time"] = 0.5;
  const std::string ts = write("ts05.json", half.dump());
  EXPECT_TRUE(IsBadInput(run_fdsid({"gap", "--model", ts, "--data", path("rec.csv"), "--meta", path("rec.meta.json")}),
                         {"\"sample_time\"", "0.5 s differs from the record's 1 s"}));
  EXPECT_TRUE(IsBadInput(run_fdsid({"gap", "--model", model, "--data", path("rec.csv"), "--meta", path("rec.meta.json"),
                                    "--json", path("rec.csv")}),
                         {"refusing to overwrite"}));
}

// Issue 17, item 4: a record with two outputs (u,y1,y2: two sensors on the
// same plant, independent noise) and a model with two outputs (C = [c; c]):
// the contracts' fields for the channels together, each channel's own report
// under "channels", the joint test; --plot draws one output and is refused
// with a way out; a two-output model against a u,y record is named.
TEST_F(CliFrf, GapOfTwoOutputsReportsEachChannelAndTheJointTest) {
  simulate(256, 8, 0.01, "rec");
  simulate(256, 8, 0.0, "clean");  // the same seed: the same multisine
  std::ifstream a(path("rec.csv")), b(path("clean.csv"));
  std::string la, lb, header;
  std::getline(a, header);
  std::getline(b, lb);
  std::ostringstream csv;
  csv << "u,y1,y2\n";
  std::mt19937_64 rng(5);
  std::normal_distribution<double> noise(0.0, 0.01);
  while (std::getline(a, la) && std::getline(b, lb)) {
    const double ua = std::stod(la.substr(0, la.find(','))), ub = std::stod(lb.substr(0, lb.find(',')));
    ASSERT_EQ(ua, ub);
    char buf[96];
    std::snprintf(buf, sizeof buf, ",%.17g\n", std::stod(lb.substr(lb.find(',') + 1)) + noise(rng));
    csv << la << buf;
  }
  write("two.csv", csv.str());
  json two = json::parse(kPintelonModel);
  two["C"].push_back(two["C"][0]);
  two["D"].push_back(two["D"][0]);
  const std::string model = write("two.json", two.dump());
  const RunResult r = run_fdsid({"gap", "--model", model, "--data", path("two.csv"), "--meta", path("rec.meta.json"),
                                 "--json", path("gap.json")});
  ASSERT_TRUE(Succeeded(r)) << r.err;
  const json j = read_json("gap.json");
  expect_gap_fields(j);
  ASSERT_EQ(j["channels"].size(), 2u);
  for (const auto& c : j["channels"]) expect_gap_fields(c);
  EXPECT_EQ(j["channels"][1]["output"], 2);
  EXPECT_TRUE(j["joint"]["tested"].get<bool>());
  EXPECT_NEAR(j["gap_before"].get<double>(),
              (j["channels"][0]["gap_before"].get<double>() + j["channels"][1]["gap_before"].get<double>()) / 2,
              1e-12 * j["gap_before"].get<double>());
  EXPECT_NE(r.out.find("== output 2 (y2)"), std::string::npos) << r.out;
  EXPECT_TRUE(IsBadInput(run_fdsid({"gap", "--model", model, "--data", path("two.csv"), "--meta",
                                    path("rec.meta.json"), "--plot", path("gap.svg")}),
                         {"--plot", "choose one with --output"}));
  EXPECT_FALSE(fs::exists(path("gap.svg")));
  EXPECT_TRUE(IsBadInput(run_fdsid({"gap", "--model", model, "--data", path("rec.csv"), "--meta", path("rec.meta.json")}),
                         {"2 outputs", "the record 1"}));
}

// Review findings 1 and 15: a 0-based meta (every line k listed as k - 1) made
// `gap` answer "no gap" with exit 0 and identify-frf print "-nan ... use fewer r".
TEST_F(CliFrf, ExcitedLinesWithoutInputPowerAreNamed) {
  simulate(256, 8, 0.01, "rec");
  json meta = read_json("rec.meta.json");
  std::vector<int> zero_based;
  for (int k : meta.at("excited_lines").get<std::vector<int>>())
    if (k - 1 >= 1) zero_based.push_back(k - 1);
  meta["excited_lines"] = zero_based;
  const std::string bad = write("zero_based.meta.json", meta.dump());
  const std::string model = write("model.json", kPintelonModel);
  EXPECT_TRUE(IsBadInput(run_fdsid({"identify-frf", "--data", path("rec.csv"), "--meta", bad}),
                         {"zero_based.meta.json", "\"excited_lines\"", "63 of the 63 listed lines carry no input power",
                          "1-based"}));
  EXPECT_TRUE(IsBadInput(run_fdsid({"gap", "--model", model, "--data", path("rec.csv"), "--meta", bad}),
                         {"63 of the 63 listed lines carry no input power"}));
  // One listed line without input among the excited ones (a user review: the
  // F-16's contiguous lines 41-307 listed 0-based as 40-306 left only line 40
  // quiet, and were accepted): refused, the line named.
  json one_more = read_json("rec.meta.json");
  std::vector<int> lines = one_more.at("excited_lines").get<std::vector<int>>();
  lines.insert(lines.begin() + 1, 2);  // an even line: the odd multisine leaves it out
  one_more["excited_lines"] = lines;
  const std::string extra = write("one_more.meta.json", one_more.dump());
  EXPECT_TRUE(IsBadInput(run_fdsid({"identify-frf", "--data", path("rec.csv"), "--meta", extra}),
                         {"one_more.meta.json", "1 of the " + std::to_string(lines.size()) +
                                                    " listed lines carries no input power (line 2:"}));
  EXPECT_TRUE(IsBadInput(run_fdsid({"gap", "--model", model, "--data", path("rec.csv"), "--meta", extra}),
                         {"carries no input power (line 2:"}));
  // The right meta passes the same test.
  EXPECT_TRUE(Succeeded(run_fdsid({"identify-frf", "--data", path("rec.csv"), "--meta", path("rec.meta.json")})));
}

// Review finding 8 of stop 47: misread inputs are refused naming their cause,
// not a neighbour's: a noise-free record's unexcited lines (their ratio 0/0
// printed "= inf, below the 1 % point"), a misspelt meta field, periods left
// too few by --skip-periods (the meta's "periods" was blamed), a negative
// count (CLI11 printed a 309-digit bound), a short first row of A ("row 2" was
// named), a --min-fit no fit can reach; and "1 period" in the singular.
TEST_F(CliFrf, MisreadInputsAreNamedByTheirCause) {
  simulate(256, 8, 0.0, "clean");
  json meta = read_json("clean.meta.json");
  std::vector<int> shifted;
  for (int k : meta.at("excited_lines").get<std::vector<int>>()) shifted.push_back(k + 1);
  meta["excited_lines"] = shifted;
  const RunResult floor = run_fdsid({"identify-frf", "--data", path("clean.csv"), "--meta",
                                     write("shifted.meta.json", meta.dump())});
  EXPECT_TRUE(IsBadInput(floor, {"carry no input power", "at the rounding floor"}));
  EXPECT_EQ(floor.err.find("inf"), std::string::npos) << floor.err;
  json typo = read_json("clean.meta.json");
  typo["peroid"] = typo["period"];
  typo.erase("period");
  EXPECT_TRUE(IsBadInput(run_fdsid({"identify-frf", "--data", path("clean.csv"), "--meta",
                                    write("typo.meta.json", typo.dump())}),
                         {"field \"period\"", "is missing", "\"peroid\" a misspelling"}));
  const std::string d = path("clean.csv"), m = path("clean.meta.json");
  EXPECT_TRUE(IsBadInput(run_fdsid({"identify-frf", "--data", d, "--meta", m, "--skip-periods", "7"}),
                         {"--skip-periods/--use-periods", "M = 1 period left by --skip-periods 7"}));
  const RunResult negative = run_fdsid({"identify-frf", "--data", d, "--meta", m, "--skip-periods", "-1"});
  EXPECT_TRUE(IsBadInput(negative, {"--skip-periods", "\"-1\" is not a whole number >= 0"}));
  EXPECT_LT(negative.err.size(), 120u) << negative.err;
  json ragged = json::parse(kPintelonModel);
  ragged["A"][0].erase(3);
  const std::string r = write("ragged.json", ragged.dump());
  EXPECT_TRUE(IsBadInput(run_fdsid({"validate", "--model", r, "--data", d, "--meta", m}),
                         {"field \"A\"", "row 2 has 4 entries, row 1 has 3"}));
  const std::string model = write("model.json", kPintelonModel);
  EXPECT_TRUE(IsBadInput(run_fdsid({"validate", "--model", model, "--data", d, "--meta", m, "--min-fit", "150"}),
                         {"--min-fit", "not a percentage <= 100"}));
  const RunResult one = run_fdsid({"validate", "--model", model, "--data", d, "--meta", m, "--skip-periods", "7"});
  ASSERT_TRUE(Succeeded(one));
  EXPECT_NE(one.out.find("averaged over 1 period,"), std::string::npos) << one.out;
}

// Review finding 4: with a noise model far too optimistic (G_var 1e-12 for
// noise of variance 2e-6), every singular value lies above the noise level and
// --order auto stopped at its cap, 19, calling it "read from the singular
// values". The warning says it is the top of the range; --max-order moves it.
TEST_F(CliFrf, AnOrderAtTheTopOfTheSearchedRangeIsSaid) {
  std::mt19937_64 rng(11);
  std::normal_distribution<double> n01(0.0, 1e-3);
  std::string text = "omega,G_re,G_im,G_var\n";
  char line[160];
  for (int k = 1; k <= 100; ++k) {
    const double w = M_PI * k / 101;
    const auto g = G_at(pintelon_plant(), std::polar(1.0, w));
    std::snprintf(line, sizeof line, "%.17g,%.17g,%.17g,1e-12\n", w, g.real() + n01(rng), g.imag() + n01(rng));
    text += line;
  }
  const std::string frf = write("optimistic.csv", text);
  const RunResult r = run_fdsid({"identify-frf", "--frf", frf, "--r", "12"});
  ASSERT_TRUE(Succeeded(r));
  EXPECT_NE(r.out.find("identified order 11 (the top of the searched range; see the warning)"), std::string::npos)
      << describe(r);
  EXPECT_NE(r.out.find("warning: order 11 is the top of the searched range (n <= 11 at r = 12)"), std::string::npos)
      << describe(r);
  const RunResult lower = run_fdsid({"identify-frf", "--frf", frf, "--r", "12", "--max-order", "6"});
  ASSERT_TRUE(Succeeded(lower));
  EXPECT_NE(lower.out.find("warning: order 6 is the top of the searched range (n <= 6 at r = 12)"), std::string::npos)
      << describe(lower);
}

// Review finding 16: the V_SUB line said "about F when model and noise model
// are right" whatever V_SUB was, also without a noise model.
TEST_F(CliFrf, VSubGetsAVerdict) {
  // The bundled record: the Eq. (36) plant with white output noise, M = 8.
  const std::string data = std::string(FDSID_SOURCE_DIR) + "/data/pintelon2002_P512_M8.csv";
  const std::string meta = std::string(FDSID_SOURCE_DIR) + "/data/pintelon2002_P512_M8.meta.json";
  const RunResult right = run_fdsid({"identify-frf", "--data", data, "--meta", meta, "--order", "4", "--json", "-"});
  ASSERT_TRUE(Succeeded(right));
  const json j = json::parse(right.out);
  EXPECT_TRUE(j.at("fit").at("available").get<bool>());
  EXPECT_FALSE(j.at("fit").at("misfit").get<bool>()) << j.at("fit").dump();
  EXPECT_EQ(j.at("fit").at("periods").get<int>(), 8);
  // Noise G_var understates 5e5-fold: V_SUB ~ 5e5 x its expected value.
  std::mt19937_64 rng(3);
  std::normal_distribution<double> n01(0.0, 1e-3);
  std::string text = "omega,G_re,G_im,G_var\n", plain = "omega,G_re,G_im\n", exact = text, twofold = text;
  char line[160];
  for (int k = 1; k <= 100; ++k) {
    const double w = M_PI * k / 101;
    const auto g = G_at(pintelon_plant(), std::polar(1.0, w));
    const double re = g.real() + n01(rng), im = g.imag() + n01(rng);
    std::snprintf(line, sizeof line, "%.17g,%.17g,%.17g,4e-12\n", w, re, im);
    text += line;
    std::snprintf(line, sizeof line, "%.17g,%.17g,%.17g,2e-6\n", w, re, im);  // E|dG|^2 = 2 (1e-3)^2
    exact += line;
    std::snprintf(line, sizeof line, "%.17g,%.17g,%.17g,1e-6\n", w, re, im);
    twofold += line;
    std::snprintf(line, sizeof line, "%.17g,%.17g,%.17g\n", w, re, im);
    plain += line;
  }
  const RunResult wrong = run_fdsid({"identify-frf", "--frf", write("optimistic.csv", text), "--order", "4"});
  ASSERT_TRUE(Succeeded(wrong));
  EXPECT_NE(wrong.out.find("(100 terms, known variances); z = "), std::string::npos) << describe(wrong);
  EXPECT_NE(wrong.out.find("warning: the model does not explain the data to the noise level"), std::string::npos)
      << describe(wrong);
  // Review finding 4 of stop 47: G_var understated twofold makes V_SUB ~ 2 x 100 - q/2, z ~ 8: Cantelli's
  // 1/(1 + z^2) ~ 0.015 passed it; Fisher's combination (here the chi-square(200) tail of 2 V_SUB) flags it.
  // The right G_var: V_SUB ~ 100 - q/2, no warning (a tail at level 1e-3 under a right model; in 200 such
  // files none was flagged, workflow.cpp).
  const RunResult two = run_fdsid({"identify-frf", "--frf", write("twofold.csv", twofold), "--order", "4"});
  ASSERT_TRUE(Succeeded(two));
  EXPECT_NE(two.out.find("warning: the model does not explain the data to the noise level"), std::string::npos)
      << describe(two);
  const RunResult fits = run_fdsid({"identify-frf", "--frf", write("exact.csv", exact), "--order", "4"});
  ASSERT_TRUE(Succeeded(fits));
  EXPECT_EQ(fits.out.find("does not explain"), std::string::npos) << describe(fits);
  const RunResult none = run_fdsid({"identify-frf", "--frf", write("plain.csv", plain), "--order", "4"});
  ASSERT_TRUE(Succeeded(none));
  EXPECT_NE(none.out.find("(unit weights: the FRF file has no G_var column, so V_SUB is no fit statistic)"),
            std::string::npos)
      << describe(none);
  EXPECT_EQ(none.out.find("does not explain"), std::string::npos) << describe(none);
}

// Review finding 4 of stop 47: the fit verdict's p is Fisher's combination of
// V_SUB's terms, exact at the true model (numerics/fisher.hpp), no longer
// Cantelli's 1/(1 + z²), which let z = 16.5 pass. The Eq. (36) plant's
// resonance (0.379 cycles/sample) lies above simulate-records' default lines
// (odd lines below P/4): the subspace estimate at r = 8 misfits (200 seeds:
// V_SUB 12-56 x its expected value, flagged in 195), and the warning names the
// refinement, whose optimum fits (its p is a tail at level 1e-3 under a right
// model: this seed's, like 199 of 200 right models' in an MC run, is above).
TEST_F(CliFrf, ASubspaceMisfitIsFlaggedAndTheRefinementNamed) {
  const std::string model = write("plant.json", kPintelonModel);
  ASSERT_TRUE(Succeeded(run_fdsid({"simulate-records", "--model", model, "--out", path("oob.csv"), "--meta-out",
                                   path("oob.meta.json"), "--period", "512", "--periods", "8", "--noise-std", "0.05",
                                   "--seed", "3"})));
  const std::vector<std::string> base = {"identify-frf", "--data", path("oob.csv"), "--meta", path("oob.meta.json"),
                                         "--order", "4", "--r", "8", "--json", "-"};
  const RunResult sub = run_fdsid(base);
  ASSERT_TRUE(Succeeded(sub));
  const json fs = json::parse(sub.out)["fit"];
  EXPECT_TRUE(fs["misfit"].get<bool>()) << fs.dump();
  EXPECT_LE(fs["p_bound"].get<double>(), 1e-3) << fs.dump();
  EXPECT_NE(json::parse(sub.out)["warnings"].dump().find("--refine ml"), std::string::npos) << sub.out;
  std::vector<std::string> refine = base;
  refine.insert(refine.end(), {"--refine", "ml"});
  const RunResult ml = run_fdsid(refine);
  ASSERT_TRUE(Succeeded(ml));
  const json fm = json::parse(ml.out)["fit"];
  EXPECT_FALSE(fm["misfit"].get<bool>()) << fm.dump();
  EXPECT_GT(json::parse(ml.out)["refinement"]["p_value"].get<double>(), 1e-3);
}

// Review finding 49: --eiv-variance without --eiv was silently ignored.
TEST_F(CliFrf, EivVarianceNeedsEiv) {
  EXPECT_TRUE(IsBadInput(run_fdsid({"identify-frf", "--data", path("r.csv"), "--meta", path("r.meta.json"),
                                    "--eiv-variance", "model"}),
                         {"--eiv-variance", "--eiv"}));
}

// A user review: out-of-range numbers were silently replaced by the defaults
// (--r 0 meant "choose r", --omega-scale -1 or nan the default scale, the JSON
// showing a value never given) and --min-input-snr without --eiv or
// --improper was ignored; a file with named columns got a message suggesting
// an edit of the file, not the options. Each is refused by its option.
TEST_F(CliFrf, OutOfRangeOrIdleOptionsAreRefusedNotDefaulted) {
  const std::string data = std::string(FDSID_SOURCE_DIR) + "/data/pintelon2002_P512_M8.csv";
  const std::string meta = std::string(FDSID_SOURCE_DIR) + "/data/pintelon2002_P512_M8.meta.json";
  const std::vector<std::string> base = {"identify-frf", "--data", data, "--meta", meta};
  const auto with = [&](std::initializer_list<std::string> extra) {
    std::vector<std::string> a = base;
    a.insert(a.end(), extra);
    return run_fdsid(a);
  };
  EXPECT_TRUE(IsBadInput(with({"--r", "0"}), {"--r", "\"0\" is not a whole number >= 2"}));
  EXPECT_TRUE(IsBadInput(with({"--r-max", "0"}), {"--r-max"}));
  for (const std::string bad : {"0", "-1", "nan", "inf"})
    EXPECT_TRUE(IsBadInput(with({"--method", "orthogonal", "--omega-scale", bad}), {"--omega-scale", "finite number > 0"}))
        << bad;
  EXPECT_TRUE(IsBadInput(with({"--min-input-snr", "5"}), {"--min-input-snr", "--eiv", "--improper"}));
  EXPECT_TRUE(IsBadInput(with({"--eiv", "--min-input-snr", "nan"}), {"--min-input-snr", "finite number >= 0"}));
  const std::string named = write("named.csv", "Force,Acc\n1,2\n");
  EXPECT_TRUE(IsBadInput(run_fdsid({"identify-frf", "--data", named, "--meta", meta}),
                         {"the header is Force, Acc", "--input NAME --output NAME"}));
}

// A user review: validate and gap scored the F-16's three outputs given in
// another order against the wrong rows of the model, each labelled with the
// wrong name (exit 0). The model's "source" names its columns; the same names
// in another order are refused, other names noted (another record of the
// same quantities is legitimate, so it is no error), the same ones silent.
TEST_F(CliFrf, ValidateAndGapCompareTheColumnsWithTheModelsSource) {
  simulate(128, 8, 1e-3, "rec");
  // Named columns: Volt, Force (another signal), Acc and Acc2 (a second sensor: Acc halved).
  std::ifstream in(path("rec.csv"));
  std::string line, text = "Volt,Force,Acc,Acc2\n";
  std::getline(in, line);  // u,y
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    const size_t comma = line.find(',');
    const double u = std::stod(line.substr(0, comma)), y = std::stod(line.substr(comma + 1));
    char buf[160];
    std::snprintf(buf, sizeof buf, "%.17g,%.17g,%.17g,%.17g\n", u, 2 * u + 0.1, y, 0.5 * y);
    text += buf;
  }
  const std::string d = write("named.csv", text), m = path("rec.meta.json");
  ASSERT_TRUE(Succeeded(run_fdsid({"identify-frf", "--data", d, "--meta", m, "--input", "Volt", "--output", "Acc",
                                   "Acc2", "--order", "4", "--r", "8", "--json", path("two.json")})));
  for (const std::string cmd : {"validate", "gap"}) {
    const RunResult swapped = run_fdsid({cmd, "--model", path("two.json"), "--data", d, "--meta", m, "--input", "Volt",
                                         "--output", "Acc2", "Acc"});
    EXPECT_TRUE(IsBadInput(swapped, {"--output Acc2 Acc", "in the order Acc Acc2", "give --output Acc Acc2"})) << cmd;
    const RunResult same = run_fdsid({cmd, "--model", path("two.json"), "--data", d, "--meta", m, "--input", "Volt",
                                      "--output", "Acc", "Acc2", "--json", "-"});
    ASSERT_EQ(same.status, 0) << cmd << describe(same);
    EXPECT_EQ(same.out.find("identified from input"), std::string::npos) << cmd;
    const RunResult other = run_fdsid({cmd, "--model", path("two.json"), "--data", d, "--meta", m, "--input", "Force",
                                       "--output", "Acc", "Acc2", "--json", "-"});
    ASSERT_TRUE(other.status == 0 || other.status == 1) << cmd << describe(other);
    EXPECT_NE(json::parse(other.out)["notes"].dump().find("identified from input(s) Volt and output(s) Acc Acc2"),
              std::string::npos)
        << cmd << other.out;
  }
}

// A user review: fdsid frf writes G_var as the sample variance over the M
// periods, and identify-frf --frf judged it as a known variance, so the true
// order's model was flagged as a misfit (p 3.6e-4) where the records gave p
// 0.074. --frf-periods M declares it: the fit verdict (expected value, law,
// p) is then the records' own, to the digit (the same numbers enter both);
// frf names the option in its summary and warns below M = 4.
TEST_F(CliFrf, AnFrfFromRecordsIsJudgedByTheSampleVarianceLawWithFrfPeriods) {
  simulate(128, 8, 1e-2, "rec");
  const std::string d = path("rec.csv"), m = path("rec.meta.json");
  const RunResult frf = run_fdsid({"frf", "--data", d, "--meta", m, "--out", path("g.csv")});
  ASSERT_TRUE(Succeeded(frf)) << describe(frf);
  EXPECT_NE(frf.out.find("identify-frf --frf " + path("g.csv") + " --frf-periods 8"), std::string::npos) << frf.out;
  const std::vector<std::string> ids = {"--order", "4", "--r", "8", "--json", "-"};
  std::vector<std::string> from_records = {"identify-frf", "--data", d, "--meta", m};
  from_records.insert(from_records.end(), ids.begin(), ids.end());
  std::vector<std::string> from_frf = {"identify-frf", "--frf", path("g.csv"), "--frf-periods", "8"};
  from_frf.insert(from_frf.end(), ids.begin(), ids.end());
  std::vector<std::string> known = {"identify-frf", "--frf", path("g.csv")};
  known.insert(known.end(), ids.begin(), ids.end());
  const RunResult a = run_fdsid(from_records), b = run_fdsid(from_frf), k = run_fdsid(known);
  ASSERT_TRUE(Succeeded(a) && Succeeded(b) && Succeeded(k)) << describe(b);
  const json fa = json::parse(a.out)["fit"], fb = json::parse(b.out)["fit"], fk = json::parse(k.out)["fit"];
  EXPECT_EQ(fb["periods"], 8) << fb.dump();
  // The same model from the same numbers: V_SUB and its law agree to rounding.
  EXPECT_NEAR(fb["v_sub"].get<double>(), fa["v_sub"].get<double>(), 1e-9 * fa["v_sub"].get<double>());
  EXPECT_DOUBLE_EQ(fb["expected"].get<double>(), fa["expected"].get<double>());
  EXPECT_NEAR(fb["p_bound"].get<double>(), fa["p_bound"].get<double>(), 1e-6 * fa["p_bound"].get<double>() + 1e-300);
  EXPECT_EQ(fk["periods"], 0) << fk.dump();  // without it: known variances, expected = T
  // The bundled record's FRF read as known variances: the true order's
  // subspace model is a misfit (p 8.9e-5), and the warning names the option
  // that judges it by its law; with it, no misfit and no hint.
  const std::string src = std::string(FDSID_SOURCE_DIR) + "/data/pintelon2002_P512_M8";
  ASSERT_TRUE(Succeeded(run_fdsid({"frf", "--data", src + ".csv", "--meta", src + ".meta.json", "--out", path("b.csv")})));
  const std::string hint = "give --frf-periods M";
  const RunResult bk = run_fdsid({"identify-frf", "--frf", path("b.csv"), "--order", "4", "--r", "8", "--json", "-"});
  const RunResult bm = run_fdsid(
      {"identify-frf", "--frf", path("b.csv"), "--frf-periods", "8", "--order", "4", "--r", "8", "--json", "-"});
  ASSERT_TRUE(Succeeded(bk) && Succeeded(bm)) << describe(bk) << describe(bm);
  EXPECT_TRUE(json::parse(bk.out)["fit"]["misfit"].get<bool>()) << bk.out;
  EXPECT_NE(json::parse(bk.out)["warnings"].dump().find(hint), std::string::npos) << bk.out;
  EXPECT_FALSE(json::parse(bm.out)["fit"]["misfit"].get<bool>()) << bm.out;
  EXPECT_EQ(json::parse(bm.out)["warnings"].dump().find(hint), std::string::npos) << bm.out;
  EXPECT_EQ(json::parse(b.out)["source"]["periods"], 8);
  EXPECT_TRUE(IsBadInput(run_fdsid({"identify-frf", "--frf", path("g.csv"), "--frf-periods", "3"}), {"--frf-periods"}));
  EXPECT_TRUE(IsBadInput(run_fdsid({"identify-frf", "--data", d, "--meta", m, "--frf-periods", "8"}), {"--frf-periods"}));
  std::ifstream in(path("g.csv"));
  std::string line, plain;
  while (std::getline(in, line)) plain += line.substr(0, line.rfind(',')) + "\n";  // G_var dropped
  EXPECT_TRUE(IsBadInput(run_fdsid({"identify-frf", "--frf", write("plain.csv", plain), "--frf-periods", "8"}),
                         {"--frf-periods", "has none"}));
  const RunResult short_frf =
      run_fdsid({"frf", "--data", d, "--meta", m, "--skip-periods", "6", "--out", path("g2.csv")});
  ASSERT_TRUE(Succeeded(short_frf)) << describe(short_frf);
  EXPECT_NE(short_frf.out.find("warning: G_var is a sample variance over only M = 2 periods"), std::string::npos)
      << short_frf.out;
}

// A user review: frf --out - put its summary on stdout after the CSV rows, so
// identify-frf refused the file ("line 130: has 1 fields"), and --json -
// appended the JSON too. The summary goes to stderr then; --json - needs a file.
TEST_F(CliFrf, AnFrfOnStdoutIsACsvIdentifyFrfReads) {
  const std::string src = std::string(FDSID_SOURCE_DIR) + "/data/pintelon2002_P512_M8";
  const RunResult r = run_fdsid({"frf", "--data", src + ".csv", "--meta", src + ".meta.json", "--out", "-"});
  ASSERT_TRUE(Succeeded(r)) << describe(r);
  EXPECT_EQ(r.out.find("wrote"), std::string::npos) << r.out.substr(r.out.size() - 300);
  EXPECT_NE(r.err.find("identify-frf --frf FILE --frf-periods 8"), std::string::npos) << r.err;
  const RunResult id =
      run_fdsid({"identify-frf", "--frf", write("stdout.csv", r.out), "--frf-periods", "8", "--order", "4"});
  EXPECT_TRUE(Succeeded(id)) << describe(id);
  EXPECT_TRUE(IsBadInput(
      run_fdsid({"frf", "--data", src + ".csv", "--meta", src + ".meta.json", "--out", "-", "--json", "-"}),
      {"--json", "needs --out FILE"}));
}

// Review finding 9: simulate-records wrote a meta identify-frf refuses (a line
// listed twice) and the non-causal periodic "steady state" of an unstable model.
TEST_F(CliFrf, SimulateRecordsRefusesWhatIdentifyFrfWouldRefuse) {
  const std::string model = write("plant.json", kPintelonModel);
  EXPECT_TRUE(IsBadInput(run_fdsid({"simulate-records", "--model", model, "--out", path("a.csv"), "--meta-out",
                                    path("a.meta.json"), "--period", "64", "--periods", "4", "--lines", "2", "2"}),
                         {"excited line 2 is listed twice"}));
  const std::string unstable = write("unstable.json", R"({"domain": "discrete", "sample_time": 1.0,
      "A": [[1.1, 0], [0, 0.5]], "B": [[1], [1]], "C": [[1, 1]], "D": [[0]]})");
  EXPECT_TRUE(IsBadInput(run_fdsid({"simulate-records", "--model", unstable, "--out", path("b.csv"), "--meta-out",
                                    path("b.meta.json"), "--period", "64", "--periods", "4"}),
                         {"pole of modulus 1.1", "no periodic steady state"}));
  EXPECT_FALSE(fs::exists(path("a.csv")));
  EXPECT_FALSE(fs::exists(path("b.csv")));
  // Review finding 28: --json, as on every subcommand.
  const RunResult ok = run_fdsid({"simulate-records", "--model", model, "--out", path("c.csv"), "--meta-out",
                                  path("c.meta.json"), "--period", "64", "--periods", "4", "--json", "-"});
  ASSERT_TRUE(Succeeded(ok));
  const json j = json::parse(ok.out);
  EXPECT_EQ(j.at("samples").get<int>(), 256);
  EXPECT_EQ(j.at("meta").at("period").get<int>(), 64);
  // gap refuses the unstable model naming its file, not the record's (a user
  // review: "…Level7.csv: model: has an unstable pole").
  const RunResult g = run_fdsid({"gap", "--model", unstable, "--data", path("c.csv"), "--meta", path("c.meta.json")});
  EXPECT_TRUE(IsBadInput(g, {"unstable.json: model", "no periodic steady state"}));
  EXPECT_EQ(g.err.find("c.csv"), std::string::npos) << describe(g);
}

// Review finding 21: three cases printed "subtle or paired nan" and then
// "targets met", with unformatted medians.
TEST_F(CliFrf, GapValidateSaysWhatItDidNotTest) {
  // The schedule's first three cases: two effect-free, one clear (no subtle or paired case).
  const RunResult r = run_fdsid({"gap-validate", "--cases", "3", "--seed", "3", "--period", "256", "--threads", "2"});
  ASSERT_TRUE(r.status == 0 || r.status == 1) << describe(r);
  EXPECT_NE(r.out.find("subtle or paired n/a (no such case)"), std::string::npos) << describe(r);
  EXPECT_NE(r.out.find("(not tested, no such case: subtle or paired)"), std::string::npos) << describe(r);
  EXPECT_EQ(r.out.find("nan"), std::string::npos) << describe(r);
}

TEST_F(CliFrf, GapValidateScoresBlindCases) {
  // 20 cases (one schedule cycle: 2 effect-free, 7 clear, 7 subtle, 4 pairs).
  // Measured exact-verdict rate over 300 cases ≈ 0.87; P(Bin(20, 0.87) < 10) <
  // 1e-5, so accuracy ≥ 0.5 fails only if the diagnosis or scoring breaks.
  const RunResult r = run_fdsid({"gap-validate", "--cases", "20", "--seed", "3", "--period", "512", "--threads", "2",
                                 "--json", path("v.json")});
  ASSERT_TRUE(r.status == 0 || r.status == 1) << describe(r);  // 1: the issue's targets missed on these 20
  const json j = read_json("v.json");
  EXPECT_EQ(j["cases"], 20);
  EXPECT_GE(j["accuracy"].get<double>(), 0.5);
  int total = 0, correct = 0;
  for (const auto& t : j["confusion"].items())
    for (const auto& v : t.value().items()) {
      total += v.value().get<int>();
      if (v.key() == t.key()) correct += v.value().get<int>();
    }
  EXPECT_EQ(total, 20);
  EXPECT_NEAR(j["accuracy"].get<double>(), correct / 20.0, 1e-12);
  EXPECT_EQ(j["rows"].size(), 20u);
  EXPECT_EQ(j["by_category"]["none"]["cases"], 2);
  EXPECT_EQ(r.status == 0, j["targets"]["met"].get<bool>());
  int noted = 0;  // the equal-noise-power note: p < effect_alpha (1e-3) in the row
  for (const auto& row : j["rows"]) noted += row["p_period_power"].get<double>() < 1e-3;
  EXPECT_EQ(j["period_power_noted"]["cases"], noted);
  EXPECT_NE(r.out.find("noise power differs between periods (noted in the report): " + std::to_string(noted) + " of 20"),
            std::string::npos) << describe(r);
  EXPECT_TRUE(IsBadInput(run_fdsid({"gap-validate", "--cases", "0"}), {}));
}

// Measured noise (gap_cases.hpp; issue 17 item 5): --noise-from records with
// any header, their period taken, M the pool's size up to 8, the JSON saying
// so; the mis-meant forms refused before any case (exit 2, one line naming
// the option). The record here: 16 periods of P = 128, a periodic column plus
// noise (pool of 8) whose standard deviation is 3 × larger in periods 9-16,
// so the pool's first four noise periods have 1/9 the power of the last
// four: every case's report must note that the noise power differs between
// periods (period_power_test, 32 line pairs: the shares of the low periods
// fall from 1/8 to ~1/40 — S in the hundreds against χ²(R − 1)); what the
// cases score is not checked (2 cases).
TEST_F(CliFrf, GapValidateOnMeasuredNoise) {
  const int P = 128, periods = 16;
  std::string csv = "Force,Accel,Fs\n";
  std::mt19937_64 g(3);
  std::normal_distribution<double> normal;
  for (int t = 0; t < P * periods; ++t)
    csv += std::to_string(std::cos(2 * M_PI * (t % P) / P)) + "," + std::to_string(std::sin(2 * M_PI * (t % P) / P) + (t < 8 * P ? 0.01 : 0.03) * normal(g)) +
           (t == 0 ? ",400\n" : ",\n");
  write("noise.csv", csv);
  write("noise.meta.json", "{\"period\": 128, \"periods\": 16, \"sample_time\": 0.0025, \"excited_lines\": [1]}");
  const std::vector<std::string> from = {"--noise-from", path("noise.csv"), "--noise-meta", path("noise.meta.json"),
                                         "--noise-input", "Force", "--noise-output", "Accel"};
  auto with = [&](std::vector<std::string> args) {
    args.insert(args.begin(), "gap-validate");
    args.insert(args.end(), from.begin(), from.end());
    return run_fdsid(args);
  };
  const RunResult r = with({"--cases", "2", "--seed", "1", "--threads", "2", "--json", path("m.json")});
  ASSERT_TRUE(r.status == 0 || r.status == 1) << describe(r);
  EXPECT_NE(r.out.find("P = 128, M = 8"), std::string::npos) << describe(r);
  EXPECT_NE(r.out.find("measured noise: 8 noise periods from 1 record(s)"), std::string::npos) << describe(r);
  const json j = read_json("m.json");
  EXPECT_TRUE(j["noise"]["measured"].get<bool>());
  EXPECT_EQ(j["noise"]["pool"], 8);
  EXPECT_EQ(j["period_power_noted"]["cases"], 2);
  for (const auto& row : j["rows"]) EXPECT_LT(row["p_period_power"].get<double>(), 1e-3) << row.dump();
  EXPECT_TRUE(IsBadInput(with({"--period", "256"}), {"--period", "128"}));
  EXPECT_TRUE(IsBadInput(with({"--periods", "9"}), {"--periods", "8"}));
  EXPECT_TRUE(IsBadInput(with({"--noise-skip-periods", "9"}), {"--noise-from", "4"}));
  EXPECT_TRUE(IsBadInput(run_fdsid({"gap-validate", "--noise-meta", path("noise.meta.json")}), {"--noise-from"}));
  EXPECT_TRUE(IsBadInput(run_fdsid({"gap-validate", "--noise-from", path("noise.csv"), "--noise-meta",
                                    path("noise.meta.json"), "--noise-output", "Accel"}),
                         {"--noise-input"}));
  EXPECT_TRUE(IsBadInput(run_fdsid({"gap-validate", "--noise-from", path("noise.csv"), "--noise-meta",
                                    path("noise.meta.json"), "--noise-input", "Force", "--noise-output", "Acc9"}),
                         {"Acc9"}));
}

// ---------------------------------------------------------------------------
// The oracle for Pintelon (2002): check --frf / --data --meta
//
// The candidates are made by `identify-frf` (fdsid's own double-precision
// implementation: correct, so it must agree) and by `identify-frf` run the
// way the classic mistakes run it (wrong data, wrong settings): each of those
// moves G by at least the noise level of the data (relative 1e-2 here, far
// above any rounding tolerance), so each must disagree.

/// An FRF file of `s` at `omega` with noise: G + N, E|N|² = var_k =
/// rel² |G_k|² (a 1 % error that varies over frequency, so unweighted and
/// weighted steps differ), circular complex normal from a fixed seed; the
/// G_var column carries var_k. `conjugate`: writes conj(G + N) (the classic
/// e^{+jωt} sign mistake); `drop`: leaves row `drop` out (1-based data row).
std::string noisy_frf_csv(const fdsid::StateSpace& s, const std::vector<double>& omega, double rel,
                          bool conjugate = false, int drop = 0, bool with_var = true) {
  std::mt19937_64 rng(11);
  std::string text = with_var ? "omega,G_re,G_im,G_var\n" : "omega,G_re,G_im\n";
  char line[160];
  for (size_t k = 0; k < omega.size(); ++k) {
    const std::complex<double> xi =
        s.domain == fdsid::Domain::Discrete ? std::polar(1.0, omega[k]) : std::complex<double>(0.0, omega[k]);
    const auto g0 = G_at(s, xi);
    const double var = rel * rel * std::norm(g0);
    std::normal_distribution<double> n(0.0, std::sqrt(var / 2));
    const double nr = n(rng), ni = n(rng);
    const std::complex<double> g = g0 + std::complex<double>(nr, ni);
    if (static_cast<int>(k) + 1 == drop) continue;
    if (with_var)
      std::snprintf(line, sizeof line, "%.17g,%.17g,%.17g,%.17g\n", omega[k], g.real(), conjugate ? -g.imag() : g.imag(), var);
    else
      std::snprintf(line, sizeof line, "%.17g,%.17g,%.17g\n", omega[k], g.real(), conjugate ? -g.imag() : g.imag());
    text += line;
  }
  return text;
}

std::vector<double> discrete_grid(int F) {
  std::vector<double> omega;
  for (int k = 0; k < F; ++k) omega.push_back(M_PI * (k + 0.5) / F);
  return omega;
}

std::vector<double> continuous_grid(int F) {
  std::vector<double> omega;
  for (int k = 0; k < F; ++k) omega.push_back(0.1 * std::pow(1000.0, k / (F - 1.0)));  // 0.1 … 100 rad/s
  return omega;
}

/// check's verdict on a candidate: exit status 0 with "AGREES" or 1 with
/// "DISAGREES", and the JSON's quantities each with distance, tolerance, ratio.
void expect_verdict(const RunResult& r, bool agree, const json& j) {
  ASSERT_FALSE(r.timed_out) << describe(r);
  ASSERT_EQ(r.status, agree ? 0 : 1) << describe(r);
  EXPECT_NE(r.out.find(agree ? "AGREES: G on the data grid" : "DISAGREES: G on the data grid"), std::string::npos)
      << r.out;
  EXPECT_EQ(j["agree"], agree);
  ASSERT_EQ(j["quantities"].size(), 3u);
  double worst = 0;
  for (const auto& q : j["quantities"]) {
    ASSERT_TRUE(q.contains("distance") && q.contains("tolerance") && q.contains("ratio")) << q.dump();
    EXPECT_GT(q["tolerance"].get<double>(), 0) << q.dump();
    worst = std::max(worst, q["ratio"].get<double>());
  }
  EXPECT_EQ(worst <= 1.0, agree) << j["quantities"].dump();
  std::printf("check: worst ratio distance/tolerance %.3g (%s)\n", worst, agree ? "agrees" : "disagrees");
}

TEST_F(CliFrf, CheckAgreesWithACorrectCandidateInEveryDomainAndMethod) {
  const std::string d = write("d.csv", noisy_frf_csv(pintelon_plant(), discrete_grid(60), 1e-2));
  const std::string c = write("c.csv", noisy_frf_csv(continuous_plant(), continuous_grid(60), 1e-2));
  std::vector<double> narrow;  // 6.4 % of [0, pi] around the resonance at 0.47 rad/sample (issue 15, item 4)
  for (int k = 0; k < 60; ++k) narrow.push_back(0.3 + 0.2 * k / 59.0);
  const std::string nb = write("nb.csv", noisy_frf_csv(pintelon_plant(), narrow, 1e-2));
  struct Case {
    std::string name, frf, domain, method;
  };
  for (const Case& k : {Case{"discrete", d, "discrete", "monomial"}, Case{"discrete-bilinear", nb, "discrete", "bilinear"},
                        Case{"discrete-orthogonal", nb, "discrete", "orthogonal"}, Case{"bilinear", c, "continuous", "bilinear"},
                        Case{"orthogonal", c, "continuous", "orthogonal"}}) {
    SCOPED_TRACE(k.name);
    const std::string cand = path(k.name + ".json");
    ASSERT_TRUE(Succeeded(run_fdsid({"identify-frf", "--frf", k.frf, "--domain", k.domain, "--method", k.method,
                                     "--order", "4", "--r", "8", "--json", cand})));
    const RunResult r = run_fdsid({"check", "--model", cand, "--frf", k.frf, "--json", path(k.name + ".check.json")});
    const json j = read_json(k.name + ".check.json");
    expect_verdict(r, true, j);
    EXPECT_EQ(j["r"], 8);
    EXPECT_EQ(j["method"], k.name == "discrete"   ? std::string("pintelon2002-alg1")
                           : k.domain == "discrete" ? "pintelon2002-alg1-" + k.method
                                                    : "pintelon2002-alg2-" + k.method);
  }
  // Records: the sample means and variances over the periods (Section 4.1).
  simulate(64, 6, 1e-3, "rec");
  ASSERT_TRUE(Succeeded(run_fdsid({"identify-frf", "--data", path("rec.csv"), "--meta", path("rec.meta.json"),
                                   "--order", "4", "--r", "8", "--json", path("rec.json")})));
  const RunResult r = run_fdsid({"check", "--model", path("rec.json"), "--data", path("rec.csv"), "--meta",
                                 path("rec.meta.json"), "--json", path("rec.check.json")});
  expect_verdict(r, true, read_json("rec.check.json"));
  // Section 5's treatments of records, read from the candidate's "source".
  for (const std::vector<std::string>& treatment :
       {std::vector<std::string>{"--eiv"}, {"--eiv", "--eiv-variance", "model"}, {"--improper"}}) {
    SCOPED_TRACE(treatment[0] + (treatment.size() > 1 ? " model" : ""));
    std::vector<std::string> args = {"identify-frf", "--data", path("rec.csv"), "--meta", path("rec.meta.json"),
                                     "--order", "4", "--r", "8", "--json", path("treated.json")};
    args.insert(args.end(), treatment.begin(), treatment.end());
    ASSERT_TRUE(Succeeded(run_fdsid(args)));
    const RunResult t = run_fdsid({"check", "--model", path("treated.json"), "--data", path("rec.csv"), "--meta",
                                   path("rec.meta.json"), "--json", path("treated.check.json")});
    expect_verdict(t, true, read_json("treated.check.json"));
  }
  // Without r in the JSON, r comes from the V_SUB selection, and the line says so.
  json bare = read_json("discrete.json");
  bare.erase("r");
  const std::string no_r = write("no_r.json", bare.dump());
  const RunResult s = run_fdsid({"check", "--model", no_r, "--frf", d, "--r", "8"});
  EXPECT_EQ(s.status, 0) << describe(s);
  // Without a method, a continuous candidate is checked as bilinear, and the
  // note says so once (a user review saw it twice on one line).
  json no_method = read_json("bilinear.json");
  no_method.erase("method");
  const RunResult m = run_fdsid({"check", "--model", write("no_method.json", no_method.dump()), "--frf", c, "--json",
                                 path("no_method.check.json")});
  EXPECT_EQ(m.status, 0) << describe(m);
  const std::string note = read_json("no_method.check.json")["note"].get<std::string>();
  const std::string said = "method: bilinear (Algorithm 2.1; neither the candidate nor --method names one)";
  ASSERT_NE(note.find(said), std::string::npos) << note;
  EXPECT_EQ(note.find(said, note.find(said) + 1), std::string::npos) << note;
}

TEST_F(CliFrf, CheckCatchesTheClassicMistakes) {
  const std::vector<double> wd = discrete_grid(60), wc = continuous_grid(60);
  const std::string d = write("d.csv", noisy_frf_csv(pintelon_plant(), wd, 1e-2));
  const std::string c = write("c.csv", noisy_frf_csv(continuous_plant(), wc, 1e-2));
  auto candidate = [&](const std::string& name, const std::string& frf, std::vector<std::string> extra) {
    std::vector<std::string> args = {"identify-frf", "--frf", frf, "--order", "4", "--r", "8", "--json", path(name)};
    args.insert(args.end(), extra.begin(), extra.end());
    EXPECT_TRUE(Succeeded(run_fdsid(args)));
    return path(name);
  };
  auto expect_disagrees = [&](const std::string& what, const std::string& cand, const std::string& frf,
                              std::vector<std::string> extra = {}) {
    SCOPED_TRACE(what);
    std::vector<std::string> args = {"check", "--model", cand, "--frf", frf, "--json", path("verdict.json")};
    args.insert(args.end(), extra.begin(), extra.end());
    const RunResult r = run_fdsid(args);
    expect_verdict(r, false, read_json("verdict.json"));
  };
  // A conjugated FRF (the e^{+jwt} convention): the same |G|, the phase mirrored. Its subspace poles lie
  // outside the unit circle; the mistaken implementation keeps them (fdsid's reflection, which check
  // refuses by name, is not the mistake under test).
  expect_disagrees("conjugated FRF",
                   candidate("conj.json", write("conj.csv", noisy_frf_csv(pintelon_plant(), wd, 1e-2, true)),
                             {"--allow-unstable"}),
                   d);
  // Unweighted steps: the G_var column ignored (unit weights).
  expect_disagrees("unweighted",
                   candidate("unw.json", write("unw.csv", noisy_frf_csv(pintelon_plant(), wd, 1e-2, false, 0, false)), {}),
                   d);
  // A dropped sample (an off-by-one reading of the file).
  expect_disagrees("dropped sample",
                   candidate("drop.json", write("drop.csv", noisy_frf_csv(pintelon_plant(), wd, 1e-2, false, 1)), {}), d);
  // An r mislabelled: identified with r = 8, labelled r = 10.
  json mis = read_json(candidate("good.json", d, {}).substr(dir_.string().size() + 1));
  mis["r"] = 10;
  expect_disagrees("r mislabelled", write("mis.json", mis.dump()), d);
  // Algorithm 2.2 labelled as 2.1.
  json orth = read_json(candidate("orth.json", c, {"--domain", "continuous", "--method", "orthogonal"})
                            .substr(dir_.string().size() + 1));
  orth["method"] = "pintelon2002-alg2-bilinear";
  expect_disagrees("orthogonal labelled bilinear", write("orth_as_bil.json", orth.dump()), c);
  // Tight (issue 13): a correct candidate with D moved by 1e-10 relative, a
  // change of G far below the noise and below the old rule's tolerance.
  json nudged = read_json("good.json");
  nudged["D"][0][0] = nudged["D"][0][0].get<double>() * (1 + 1e-10);
  expect_disagrees("D moved by 1e-10", write("nudged.json", nudged.dump()), d);
  // (An errors-in-variables estimate passed off as the plain one is not among
  // these: on simulate-records' flat multisine, |U_k| constant and no input
  // noise, Section 5's ratio data are the plain data scaled by one complex
  // number per frequency of constant modulus, and both estimates coincide.)
}

// Issue 13: the order is a setting of the algorithm, like r: a correct
// estimate at order 2 agrees with the reference at order 2, and check names
// the order the data support (identify-frf --order auto at the candidate's r).
TEST_F(CliFrf, CheckNamesTheOrderTheDataSupport) {
  const std::string d = write("d.csv", noisy_frf_csv(pintelon_plant(), discrete_grid(60), 1e-3));
  ASSERT_TRUE(Succeeded(run_fdsid({"identify-frf", "--frf", d, "--order", "2", "--r", "8", "--json", path("low.json")})));
  const RunResult r = run_fdsid({"check", "--model", path("low.json"), "--frf", d, "--json", path("verdict.json")});
  const json v = read_json("verdict.json");
  expect_verdict(r, true, v);
  EXPECT_NE(r.out.find("the data support order 4"), std::string::npos) << r.out;
  EXPECT_NE(v["order_note"].get<std::string>().find("candidate has order 2"), std::string::npos) << v["order_note"];
  // A candidate of the right order carries no such note.
  ASSERT_TRUE(Succeeded(run_fdsid({"identify-frf", "--frf", d, "--order", "4", "--r", "8", "--json", path("ok.json")})));
  const RunResult ok = run_fdsid({"check", "--model", path("ok.json"), "--frf", d, "--json", path("ok_verdict.json")});
  expect_verdict(ok, true, read_json("ok_verdict.json"));
  EXPECT_EQ(read_json("ok_verdict.json")["order_note"], "");
}

// Review finding 13: a power basis numerically dependent on a narrow band was
// reported as "C_Y is not positive definite (variances too small)". The
// message names the band and the ways out.
TEST_F(CliFrf, ANarrowBandNamesTheBandNotTheVariances) {
  std::vector<double> omega;
  for (int k = 0; k < 40; ++k) omega.push_back(0.05 + 0.05 * k / 39.0);  // 1.6 % of [0, pi]
  const std::string f = write("narrow.csv", frf_csv(pintelon_plant(), omega, 1e-6));
  const RunResult r = run_fdsid({"identify-frf", "--frf", f, "--order", "4", "--r", "30"});
  EXPECT_TRUE(IsBadInput(r, {"rad/sample", "% of [0, pi]", "--r", "--method bilinear", "--domain continuous"}));
  EXPECT_EQ(r.err.find("variances too small"), std::string::npos) << r.err;
  // The fix it names (issue 15, item 4): the bilinear basis on the Tustin
  // frequencies identifies the same file, in double and in 50 digits, with the
  // same poles (the noise is 1e-3 relative: both are estimates of one model).
  const RunResult b = run_fdsid({"identify-frf", "--frf", f, "--order", "4", "--r", "12", "--method", "bilinear",
                                 "--json", path("nb.json")});
  ASSERT_TRUE(Succeeded(b)) << describe(b);
  const json jb = read_json("nb.json");
  EXPECT_EQ(jb["method"], "pintelon2002-alg1-bilinear");
  EXPECT_EQ(jb["domain"], "discrete");
  EXPECT_GT(jb["omega_scale"].get<double>(), 0.05);
  EXPECT_LT(jb["omega_scale"].get<double>(), 0.1);
  const RunResult h = run_fdsid({"identify-frf", "--frf", f, "--order", "4", "--r", "12", "--method", "bilinear",
                                 "--precision", "high", "--json", path("nbh.json")});
  ASSERT_TRUE(Succeeded(h)) << describe(h);
  EXPECT_EQ(read_json("nbh.json")["method"], "pintelon2002-alg1-bilinear");
  // Algorithm 2.2's orthogonal bases on the same axis tan(omega/2).
  const RunResult o = run_fdsid({"identify-frf", "--frf", f, "--order", "4", "--r", "12", "--method", "orthogonal",
                                 "--json", path("nbo.json")});
  ASSERT_TRUE(Succeeded(o)) << describe(o);
  EXPECT_EQ(read_json("nbo.json")["method"], "pintelon2002-alg1-orthogonal");
  // A name of the other domain is refused by name, before any work.
  EXPECT_TRUE(IsBadInput(run_fdsid({"identify-frf", "--frf", f, "--order", "4", "--method", "monomial", "--domain",
                                    "continuous"}),
                         {"--method", "discrete-time"}));
  EXPECT_TRUE(IsBadInput(run_fdsid({"identify-frf", "--frf", f, "--order", "4", "--omega-scale", "0.1"}),
                         {"--omega-scale", "monomial", "--method bilinear"}));
  EXPECT_TRUE(IsBadInput(run_fdsid({"identify-frf", "--frf", f, "--order", "4", "--method", "bilinear", "--omega-scale",
                                    "4"}),
                         {"omega_scale", "(0, pi)"}));
}

// identify-frf --precision high repeats Section 5's treatments as check does:
// its model is, digit for digit, the reference model check compares with.
TEST_F(CliFrf, HighPrecisionTreatsRecordsAsCheckDoes) {
  simulate(64, 6, 1e-3, "rec");
  for (const std::string treatment : {"--eiv", "--improper"}) {
    SCOPED_TRACE(treatment);
    const std::vector<std::string> common = {"identify-frf", "--data", path("rec.csv"), "--meta",
                                             path("rec.meta.json"), "--order", "4", "--r", "8", treatment};
    std::vector<std::string> dbl = common, high = common;
    dbl.insert(dbl.end(), {"--json", path("double.json")});
    high.insert(high.end(), {"--precision", "high", "--json", path("high.json")});
    ASSERT_TRUE(Succeeded(run_fdsid(dbl)));
    ASSERT_TRUE(Succeeded(run_fdsid(high)));
    const RunResult r = run_fdsid({"check", "--model", path("double.json"), "--data", path("rec.csv"), "--meta",
                                   path("rec.meta.json"), "--json", path("check.json")});
    ASSERT_EQ(r.status, 0) << describe(r);
    EXPECT_EQ(read_json("high.json")["A"], read_json("check.json")["reference_model"]["A"]);
    EXPECT_EQ(read_json("high.json")["poles"], read_json("check.json")["reference_model"]["poles"]);
  }
}

TEST_F(CliFrf, CheckRefusesWhatItCannotCompare) {
  const std::string d = write("d.csv", noisy_frf_csv(pintelon_plant(), discrete_grid(40), 1e-2));
  ASSERT_TRUE(Succeeded(run_fdsid({"identify-frf", "--frf", d, "--order", "4", "--r", "8", "--json", path("c.json")})));
  const std::string cand = path("c.json");
  EXPECT_TRUE(IsBadInput(run_fdsid({"check", "--model", cand, "--frf", d, "--r", "9"}), {"--r", "contradicts", "8"}));
  // The candidate's basis is Algorithm 1's monomial one: another basis contradicts it.
  EXPECT_TRUE(IsBadInput(run_fdsid({"check", "--model", cand, "--frf", d, "--method", "orthogonal"}),
                         {"--method", "contradicts", "monomial"}));
  EXPECT_TRUE(IsBadInput(run_fdsid({"check", "--model", cand, "--frf", d, "--method", "spline"}),
                         {"--method", "not monomial, bilinear or orthogonal"}));
  EXPECT_TRUE(IsBadInput(run_fdsid({"check", "--model", cand}), {"--frf"}));
  json spectral = read_json("c.json");
  spectral["method"] = "akcay2011";
  EXPECT_TRUE(IsBadInput(run_fdsid({"check", "--model", write("s.json", spectral.dump()), "--frf", d}),
                         {"spectral factor", "--data"}));
  spectral["method"] = "pintelon2002-alg3";  // every FRF method is named in the refusal
  EXPECT_TRUE(IsBadInput(run_fdsid({"check", "--model", write("alg3.json", spectral.dump()), "--frf", d}),
                         {"field \"method\"", "is not pintelon2002-alg1, pintelon2002-alg1-bilinear, "
                          "pintelon2002-alg1-orthogonal, pintelon2002-alg2-bilinear or pintelon2002-alg2-orthogonal"}));
  json cont = read_json("c.json");
  cont["domain"] = "continuous";
  cont["sample_time"] = 0;
  EXPECT_TRUE(IsBadInput(run_fdsid({"check", "--model", write("cont.json", cont.dump()), "--frf", d}),
                         {"continuous-time model", "pintelon2002-alg1"}));
  EXPECT_TRUE(IsBadInput(run_fdsid({"check", "--model", cand, "--data", d, "--r", "8"}), {"--r", "--meta"}));
  json eiv_frf = read_json("c.json");
  eiv_frf["source"] = {{"data", "x.csv"}, {"errors_in_variables", json::object()}};
  EXPECT_TRUE(IsBadInput(run_fdsid({"check", "--model", write("eiv_frf.json", eiv_frf.dump()), "--frf", d}),
                         {"--eiv", "records"}));
  // Records whose sample time is not the candidate's.
  simulate(32, 4, 1e-3, "rec");
  json rec_meta = read_json("rec.meta.json");
  rec_meta["sample_time"] = 0.5;
  const std::string meta = write("half.meta.json", rec_meta.dump());
  EXPECT_TRUE(IsBadInput(run_fdsid({"check", "--model", cand, "--data", path("rec.csv"), "--meta", meta}),
                         {"sample_time", "0.5"}));
  ASSERT_TRUE(Succeeded(run_fdsid({"identify-frf", "--data", path("rec.csv"), "--meta", path("rec.meta.json"),
                                   "--order", "4", "--r", "8", "--json", path("plain.json")})));
  EXPECT_TRUE(IsBadInput(run_fdsid({"check", "--model", path("plain.json"), "--data", path("rec.csv"), "--meta",
                                    path("rec.meta.json"), "--eiv"}),
                         {"contradict", "source"}));
}

}  // namespace

// ---------------------------------------------------------------------------
// Real records as they come (issue 14, item 4): columns by name, a transient
// period skipped, records turned into an FRF file, a model validated on a record.

namespace {

/// The u,y record `csv` rewritten as a measurement file would have it: a
/// quoted header with other columns ("Time", "Voltage", an "Fs" column empty
/// below its first row), a trailing comma on every line, and `transient`
/// leading rows of a start-up transient (garbage) before the periodic part.
/// The u and y cells keep their text, so the numbers read back exactly.
std::string as_measured(const std::string& csv, int transient) {
  std::istringstream in(csv);
  std::string line, out = "\"Time\",\"Force\",\"Voltage\",\"Acceleration1\",\"Fs\",\n";
  std::getline(in, line);  // u,y
  char buf[200];
  for (int t = 0; t < transient; ++t) {
    std::snprintf(buf, sizeof buf, "%d,%g,0.5,%g,%s,\n", t, 100.0 * std::sin(t), -50.0 * std::cos(t), t == 0 ? "1" : "");
    out += buf;
  }
  for (int t = transient; std::getline(in, line); ++t) {
    const auto comma = line.find(',');
    out += std::to_string(t) + "," + line.substr(0, comma) + ",0.25," + line.substr(comma + 1) + "," +
           (t == 0 ? "1" : "") + ",\n";
  }
  return out;
}

}  // namespace

TEST_F(CliFrf, RecordsAsTheyComeColumnsByNameAndSkippedPeriods) {
  simulate(256, 8, 1e-3, "rec");
  std::ifstream f(path("rec.csv"));
  const std::string csv((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  const std::string measured = write("measured.csv", as_measured(csv, 256));
  json meta = read_json("rec.meta.json");
  meta["periods"] = 9;  // the transient period and the 8 periodic ones
  const std::string meta9 = write("measured.meta.json", meta.dump());
  ASSERT_TRUE(Succeeded(run_fdsid({"identify-frf", "--data", path("rec.csv"), "--meta", path("rec.meta.json"), "--order",
                                   "4", "--r", "8", "--json", path("plain.json")})));
  ASSERT_TRUE(Succeeded(run_fdsid({"identify-frf", "--data", measured, "--meta", meta9, "--input", "Force", "--output",
                                   "Acceleration1", "--skip-periods", "1", "--order", "4", "--r", "8", "--json",
                                   path("named.json")})));
  // The same numbers reach the algorithm: the same model, bit for bit.
  const json plain = read_json("plain.json"), named = read_json("named.json");
  EXPECT_EQ(plain["poles"], named["poles"]);
  EXPECT_EQ(plain["A"], named["A"]);
  EXPECT_EQ(named["source"]["input_columns"], json::array({"Force"}));
  EXPECT_EQ(named["source"]["skip_periods"], 1);
  // check repeats the candidate's reading from its "source" (no options needed).
  const RunResult chk = run_fdsid({"check", "--model", path("named.json"), "--data", measured, "--meta", meta9,
                                   "--json", path("verdict.json")});
  EXPECT_EQ(chk.status, 0) << describe(chk);
  EXPECT_TRUE(IsBadInput(run_fdsid({"check", "--model", path("named.json"), "--data", measured, "--meta", meta9,
                                    "--input", "Voltage", "--output", "Acceleration1", "--skip-periods", "1"}),
                         {"contradict the candidate"}));
  // A user review: options selecting periods against a candidate that used
  // them all read DISAGREES; they contradict its source as much.
  EXPECT_TRUE(IsBadInput(run_fdsid({"check", "--model", path("plain.json"), "--data", path("rec.csv"), "--meta",
                                    path("rec.meta.json"), "--skip-periods", "1"}),
                         {"contradict the candidate", "every column and period"}));
  // Bad selections are named, before any work.
  EXPECT_TRUE(IsBadInput(run_fdsid({"identify-frf", "--data", measured, "--meta", meta9, "--input", "force", "--output",
                                    "Acceleration1"}),
                         {"--input \"force\" is not a column", "Time, Force, Voltage, Acceleration1, Fs"}));
  EXPECT_TRUE(IsBadInput(run_fdsid({"identify-frf", "--data", measured, "--meta", meta9, "--input", "Force"}),
                         {"--input", "--output"}));
  EXPECT_TRUE(IsBadInput(run_fdsid({"identify-frf", "--data", measured, "--meta", meta9, "--input", "Force", "--output",
                                    "Acceleration1", "--skip-periods", "9"}),
                         {"--skip-periods", "leaves no period"}));
  EXPECT_TRUE(IsBadInput(run_fdsid({"identify-frf", "--data", measured, "--meta", meta9, "--input", "Fs", "--output",
                                    "Acceleration1"}),
                         {"line 3", "column Fs", "empty value"}));
  EXPECT_TRUE(IsBadInput(run_fdsid({"identify-frf", "--frf", write("g.csv", frf_csv(pintelon_plant(), {0.5, 1.0}, 1e-6)),
                                    "--skip-periods", "1"}),
                         {"--skip-periods", "records"}));
  // gap takes the same options.
  const std::string model = write("plant.json", kPintelonModel);
  const RunResult gap = run_fdsid({"gap", "--model", model, "--data", measured, "--meta", meta9, "--input", "Force",
                                   "--output", "Acceleration1", "--skip-periods", "1", "--json", path("gap.json")});
  EXPECT_EQ(gap.status, 0) << describe(gap);
}

// fdsid frf: G = Y/U at the excited lines and G_var = E|dG|^2 (first order).
// Statistical checks at a stated level (each fails a correct implementation
// with probability < 1e-6): white output noise of std sigma, noise-free input,
// M periods, the unitary DFT of Eq. (4), so E|dY_k|^2 = sigma^2 and
// E|dG_k|^2 = sigma^2 / (M |U_k|^2).
TEST_F(CliFrf, FrfFromRecordsCarriesTheFrfAndItsVariance) {
  const int P = 256, M = 8;
  const double sigma = 1e-2;
  simulate(P, M, 0.0, "clean");
  simulate(P, M, sigma, "noisy");  // the same seed: the same multisine
  ASSERT_TRUE(Succeeded(run_fdsid({"frf", "--data", path("noisy.csv"), "--meta", path("noisy.meta.json"), "--out",
                                   path("g.csv"), "--json", path("frf.json")})));
  const fdsid::FrfData g = fdsid::read_frf_csv(path("g.csv"), fdsid::Domain::Discrete);
  const json meta = read_json("noisy.meta.json");
  const std::vector<int> lines = meta["excited_lines"].get<std::vector<int>>();
  ASSERT_EQ(g.frequencies(), static_cast<int>(lines.size()));
  // U_k of one period of the noise-free input (unitary DFT, direct sums).
  std::ifstream f(path("clean.csv"));
  std::string line;
  std::getline(f, line);
  std::vector<double> u;
  for (int t = 0; t < P && std::getline(f, line); ++t) u.push_back(std::stod(line.substr(0, line.find(','))));
  ASSERT_EQ(static_cast<int>(u.size()), P);
  const fdsid::StateSpace plant = pintelon_plant();
  double T = 0, ratio_mean = 0;
  for (int i = 0; i < g.frequencies(); ++i) {
    const int k = lines[i];
    EXPECT_NEAR(g.omega(i), 2 * M_PI * k / P, 1e-15) << "line " << k;
    std::complex<double> U = 0;
    for (int t = 0; t < P; ++t) U += u[t] * std::polar(1.0, -2 * M_PI * k * t / P);
    U /= std::sqrt(double(P));
    const double truth_var = sigma * sigma / (M * std::norm(U));
    const std::complex<double> G_true = fdsid::transfer(plant, std::polar(1.0, 2 * M_PI * k / P))(0, 0);
    T += std::norm(g.Y[i](0, 0) - G_true) / truth_var;  // Exp(1) each at the true variance
    ratio_mean += g.variance[i](0, 0) / truth_var;        // chi2_{2(M-1)} / (2(M-1)) each
  }
  const double F = g.frequencies();
  ratio_mean /= F;
  // T: sum of F Exp(1) terms, mean F, sd sqrt(F); 5 sd.
  EXPECT_NEAR(T, F, 5 * std::sqrt(F)) << "G = Y/U misses the truth beyond its own variance";
  // The estimated variance's mean over the lines: mean 1, sd sqrt(1 / ((M-1) F)); 5 sd.
  EXPECT_NEAR(ratio_mean, 1.0, 5 * std::sqrt(1.0 / ((M - 1) * F))) << "G_var is not E|dG|^2";
  // Identification from the file it wrote: the Eq. (36) plant's four poles.
  ASSERT_TRUE(Succeeded(run_fdsid({"identify-frf", "--frf", path("g.csv"), "--order", "4", "--r", "8", "--json",
                                   path("from_frf.json")})));
  EXPECT_EQ(read_json("from_frf.json")["poles"].size(), 4u);
  // A record with two outputs has no FRF file (one channel), and says how to choose one.
  EXPECT_TRUE(IsBadInput(run_fdsid({"frf", "--data", write("two.csv", "u,y1,y2\n1,2,3\n"), "--meta",
                                    path("noisy.meta.json"), "--out", path("two_g.csv")}),
                         {"--input", "--output"}));
}

// fdsid validate: MATLAB compare's fit of a model on a record.
TEST_F(CliFrf, ValidateScoresAModelOnARecord) {
  simulate(256, 4, 0.0, "rec");
  const std::string truth = write("plant.json", kPintelonModel);
  // The true model reproduces its own noise-free steady state to rounding:
  // NRMSE <= 10 log2(P) u max|G|/min|G| = 10 * 8 * 1.1e-16 * 100 ~ 1e-12 (the
  // plant's |G| spans less than 100 over the lines); 1e-10 stated.
  ASSERT_TRUE(Succeeded(run_fdsid({"validate", "--model", truth, "--data", path("rec.csv"), "--meta",
                                   path("rec.meta.json"), "--json", path("fit.json")})));
  const json fit = read_json("fit.json");
  ASSERT_EQ(fit["outputs"].size(), 1u);
  EXPECT_LE(fit["outputs"][0]["nrmse"].get<double>(), 1e-10);
  // A gain error of 10 %: yhat = 1.1 y, so NRMSE = 0.1 and the fit 90 % exactly
  // (y has no DC line: its mean is rounding).
  json gain = json::parse(kPintelonModel);
  for (auto& c : gain["C"][0]) c = 1.1 * std::stod(c.get<std::string>());
  gain["D"][0][0] = 1.1 * std::stod(gain["D"][0][0].get<std::string>());
  const std::string wrong = write("gain.json", gain.dump());
  const RunResult r = run_fdsid({"validate", "--model", wrong, "--data", path("rec.csv"), "--meta",
                                 path("rec.meta.json"), "--min-fit", "95", "--json", path("gain_fit.json")});
  EXPECT_EQ(r.status, 1) << describe(r);
  EXPECT_NEAR(read_json("gain_fit.json")["outputs"][0]["fit_percent"].get<double>(), 90.0, 1e-8);
  // A model of another sample time, or with a pole outside the circle, is refused.
  json slow = json::parse(kPintelonModel);
  slow["sample_time"] = 0.5;
  EXPECT_TRUE(IsBadInput(run_fdsid({"validate", "--model", write("slow.json", slow.dump()), "--data", path("rec.csv"),
                                    "--meta", path("rec.meta.json")}),
                         {"sample_time", "differs"}));
  json unstable = json::parse(kPintelonModel);
  unstable["A"][0][0] = "1.5";
  EXPECT_TRUE(IsBadInput(run_fdsid({"validate", "--model", write("unstable.json", unstable.dump()), "--data",
                                    path("rec.csv"), "--meta", path("rec.meta.json")}),
                         {"unstable pole"}));
  // Review finding 5 of stop 47: a model identified on the lines below P/4 (simulate-records' default)
  // scored on a record of all odd lines below P/2 says that the lines above its band are extrapolation;
  // on the record it was identified from, no such word.
  const std::string plant = write("plant.json", kPintelonModel);
  ASSERT_TRUE(Succeeded(run_fdsid({"simulate-records", "--model", plant, "--out", path("low.csv"), "--meta-out",
                                   path("low.meta.json"), "--period", "256", "--noise-std", "1e-3"})));
  ASSERT_TRUE(Succeeded(run_fdsid({"identify-frf", "--data", path("low.csv"), "--meta", path("low.meta.json"),
                                   "--order", "4", "--json", path("low_model.json")})));
  const RunResult wide = run_fdsid({"validate", "--model", path("low_model.json"), "--data", path("rec.csv"), "--meta",
                                    path("rec.meta.json"), "--json", path("wide_fit.json")});
  ASSERT_TRUE(Succeeded(wide));
  // rec: the odd lines 1 ... 127 of P = 256; low: the odd lines below 64, 1 ... 63.
  EXPECT_NE(wide.out.find("warning: 32 of the record's 64 excited lines lie outside the band the model was identified "
                          "on (0.003906 to 0.2461 Hz"),
            std::string::npos)
      << wide.out;
  EXPECT_NE(wide.out.find("32 above it (up to 0.4961 Hz)"), std::string::npos) << wide.out;
  EXPECT_EQ(read_json("wide_fit.json")["warnings"].size(), 1u);
  // gap says it too (a user review: a meta with sample_time in ms typed as s put every line outside, unsaid).
  // (rec.csv is noise-free, which gap refuses: the same lines with noise.)
  std::vector<std::string> noisy = {"simulate-records", "--model", plant, "--out", path("wide.csv"), "--meta-out",
                                    path("wide.meta.json"), "--period", "256", "--noise-std", "1e-3", "--lines"};
  for (int k = 1; k < 128; k += 2) noisy.push_back(std::to_string(k));
  ASSERT_TRUE(Succeeded(run_fdsid(noisy)));
  const RunResult gap_wide = run_fdsid({"gap", "--model", path("low_model.json"), "--data", path("wide.csv"), "--meta",
                                        path("wide.meta.json"), "--json", path("wide_gap.json")});
  ASSERT_TRUE(gap_wide.status == 0 || gap_wide.status == 1) << describe(gap_wide);
  EXPECT_NE(gap_wide.out.find("warning: 32 of the record's 64 excited lines lie outside the band"), std::string::npos)
      << gap_wide.out;
  EXPECT_EQ(read_json("wide_gap.json")["warnings"].size(), 1u);
  const RunResult own = run_fdsid({"validate", "--model", path("low_model.json"), "--data", path("low.csv"), "--meta",
                                   path("low.meta.json")});
  ASSERT_TRUE(Succeeded(own));
  EXPECT_EQ(own.out.find("warning"), std::string::npos) << own.out;
  // A user review: the fit on the model's own identification record read as
  // a validation. It is named so; another record is not.
  EXPECT_NE(own.out.find("note: this is the record the model was identified from (its source.data): the fit is "
                         "in-sample"),
            std::string::npos)
      << own.out;
  EXPECT_EQ(wide.out.find("in-sample"), std::string::npos) << wide.out;
  // Review finding 2 of stop 48: a model whose own file says it is unusable in double precision is named
  // by validate, gap and simulate-records (the same model marked usable, above, draws no word).
  json unusable = read_json("low_model.json");
  ASSERT_TRUE(unusable["diagnostics"]["usable"].get<bool>());
  unusable["diagnostics"]["usable"] = false;
  const std::string marked = write("unusable_model.json", unusable.dump());
  const std::vector<std::vector<std::string>> readers = {
      {"validate", "--model", marked, "--data", path("low.csv"), "--meta", path("low.meta.json")},
      {"gap", "--model", marked, "--data", path("low.csv"), "--meta", path("low.meta.json")},
      {"simulate-records", "--model", marked, "--out", path("again.csv"), "--meta-out", path("again.meta.json"),
       "--period", "256"}};
  for (const auto& args : readers) {
    const RunResult r = run_fdsid(args);
    ASSERT_TRUE(Succeeded(r)) << describe(r);
    EXPECT_NE(r.out.find("warning: " + marked + " says its estimate is unusable in double precision"),
              std::string::npos)
        << args[0] << ": " << r.out;
  }
}

// Review finding 38: a precision warning says whether the model is usable,
// and --strict turns "unusable" into exit 1 with nothing written. An order
// above the data's (6 for the fourth-order plant, noise-free) puts sigma_5,
// sigma_6 of step 1c at the rounding level: the condition sigma_1/sigma_6 is
// ~1/u, and the two extra poles are wherever rounding puts them (G on the
// grid stays right: the extra modes cancel there). Which of two honest
// outcomes follows is itself decided by rounding: the two rounding-level
// singular vectors make step 2's shifted observability matrix rank deficient
// or not (on one build, r = 9, 10, 12 refused and r = 8, 11, 14 warned; a
// change of the QR's blocking moved r = 10 from one to the other). Either way
// the user must hear it: exit 0 with the UNUSABLE warning naming the poles
// set by rounding (pole_error_estimate >= 1, usable = false in the JSON), or
// exit 2 naming step 2's rank; and --strict never writes the model.
TEST_F(CliFrf, AnUnusableEstimateIsSaidAndStrictRefusesIt) {
  const std::string d = write("clean.csv", frf_csv(pintelon_plant(), discrete_grid(60), 1e-6));
  int warned = 0;
  for (const std::string r_value : {"8", "10", "11"}) {
    const std::string json_path = path("m" + r_value + ".json");
    const RunResult r = run_fdsid({"identify-frf", "--frf", d, "--order", "6", "--r", r_value, "--json", json_path});
    if (r.status == 0) {
      ++warned;
      EXPECT_NE(r.out.find("warning: UNUSABLE in double precision"), std::string::npos) << r.out;
      EXPECT_NE(r.out.find("set by rounding"), std::string::npos) << r.out;
      const json m = read_json("m" + r_value + ".json");
      EXPECT_FALSE(m["diagnostics"]["usable"].get<bool>());
      EXPECT_GE(m["diagnostics"]["pole_error_estimate"].get<double>(), 1.0);
    } else {
      EXPECT_TRUE(IsBadInput(r, {"step 2", "rank"})) << describe(r);
      EXPECT_FALSE(fs::exists(json_path));
    }
    const std::string strict_path = path("strict" + r_value + ".json");
    const RunResult s = run_fdsid({"identify-frf", "--frf", d, "--order", "6", "--r", r_value, "--strict", "--json",
                                   strict_path});
    EXPECT_NE(s.status, 0) << describe(s);
    if (r.status == 0) {
      EXPECT_EQ(s.status, 1) << describe(s);
    }
    if (s.status == 1) {
      EXPECT_NE(s.err.find("--strict: the estimate is unusable"), std::string::npos) << s.err;
    }
    EXPECT_FALSE(fs::exists(strict_path));
  }
  // The warning path itself must be exercised: all three refusing would leave
  // it untested here (it is also reached by the unit tests' precision cases).
  EXPECT_GE(warned, 1);
  // The right order is usable, warns of nothing, and --strict lets it through.
  const RunResult ok = run_fdsid({"identify-frf", "--frf", d, "--order", "4", "--r", "8", "--strict", "--json",
                                  path("ok.json")});
  EXPECT_EQ(ok.status, 0) << describe(ok);
  EXPECT_EQ(ok.out.find("precision"), std::string::npos) << ok.out;
  EXPECT_TRUE(read_json("ok.json")["diagnostics"]["usable"].get<bool>());
}

// Review findings 11 and 36: FRF files in Hz or rad/s with a sample time (as
// MATLAB's idfrd and python-control's frd keep them). The same samples with
// the omega column in rad/sample, in Hz and in rad/s identify the same model
// (the conversion adds at most a few u relative to ω, i.e. a few u times
// max ω|G'|/|G| ≈ 7 for this plant relative to G: inside expect_exact_poles'
// allowance of 100 u κ); the model carries Ts; check repeats the conversion
// from the candidate's "source"; without the options the Hz file is refused
// naming them.
TEST_F(CliFrf, FrfFileInHzOrRadPerSecondWithASampleTime) {
  const double Ts = 0.0025;  // 400 Hz, as the F-16 record
  const std::vector<double> omega = discrete_grid(40);
  const std::string per_sample = frf_csv(pintelon_plant(), omega, 1e-6);
  std::string hz = "omega,G_re,G_im,G_var\n", rad_s = hz;
  std::istringstream lines(per_sample);
  std::string line;
  std::getline(lines, line);  // header
  char buf[64];
  while (std::getline(lines, line)) {
    const size_t comma = line.find(',');
    const double w = std::stod(line.substr(0, comma));
    std::snprintf(buf, sizeof buf, "%.17g", w / (2 * M_PI * Ts));
    hz += buf + line.substr(comma) + "\n";
    std::snprintf(buf, sizeof buf, "%.17g", w / Ts);
    rad_s += buf + line.substr(comma) + "\n";
  }
  const std::string f_hz = write("g_hz.csv", hz), f_rad_s = write("g_rad_s.csv", rad_s);
  for (const auto& [file, unit] : {std::pair{f_hz, std::string("hz")}, std::pair{f_rad_s, std::string("rad")}}) {
    SCOPED_TRACE(unit);
    const std::string out = "m_" + unit + ".json";
    const RunResult r = run_fdsid({"identify-frf", "--frf", file, "--frequency-unit", unit, "--sample-time", "0.0025",
                                   "--order", "4", "--r", "8", "--json", path(out)});
    ASSERT_TRUE(Succeeded(r));
    const json j = read_json(out);
    expect_exact_poles(pintelon_plant(), j);
    EXPECT_EQ(j["sample_time"].get<double>(), Ts);
    EXPECT_EQ(j["source"]["sample_time"], "0.0025");
    EXPECT_EQ(j["source"]["frequency_unit"], unit);  // as given, so that check reads it the same way
    const RunResult c = run_fdsid({"check", "--model", path(out), "--frf", file}, 600);
    EXPECT_EQ(c.status, 0) << describe(c);
  }
  EXPECT_TRUE(IsBadInput(run_fdsid({"identify-frf", "--frf", f_hz, "--order", "4"}),
                         {"rad/sample is outside [0, pi]", "--frequency-unit", "--sample-time"}));
  // Review finding 3 of stop 47: the odd lines of a period P = 128 in cycles/sample, (2k + 1)/128 up to
  // 63/128, lie below 1/2 < pi, so the Nyquist check cannot see them; the grid k/P can. --frequency-unit
  // hz reads them as the plant (the same exact poles); --frequency-unit rad reads them as written, and
  // says so in "source".
  std::vector<double> odd_lines;
  for (int k = 0; k < 32; ++k) odd_lines.push_back(2 * M_PI * (2 * k + 1) / 128);
  std::istringstream rows(frf_csv(pintelon_plant(), odd_lines, 1e-6));
  std::string cycles;
  std::getline(rows, cycles);
  cycles += "\n";
  for (int k = 0; std::getline(rows, line); ++k) {
    std::snprintf(buf, sizeof buf, "%.17g", (2 * k + 1) / 128.0);
    cycles += buf + line.substr(line.find(',')) + "\n";
  }
  const std::string f_cycles = write("g_cycles.csv", cycles);
  EXPECT_TRUE(IsBadInput(run_fdsid({"identify-frf", "--frf", f_cycles, "--order", "4"}),
                         {"k/128", "cycles/sample", "--frequency-unit hz", "--frequency-unit rad"}));
  ASSERT_TRUE(Succeeded(run_fdsid({"identify-frf", "--frf", f_cycles, "--frequency-unit", "hz", "--order", "4",
                                   "--r", "8", "--json", path("m_cycles.json")})));
  expect_exact_poles(pintelon_plant(), read_json("m_cycles.json"));
  ASSERT_TRUE(Succeeded(run_fdsid({"identify-frf", "--frf", f_cycles, "--frequency-unit", "rad", "--order", "4",
                                   "--r", "8", "--json", path("m_said_rad.json")})));
  EXPECT_EQ(read_json("m_said_rad.json")["source"]["frequency_unit"], "rad");
  // Hz without a sample time is cycles/sample: 400 Hz read so lies above the Nyquist frequency.
  EXPECT_TRUE(IsBadInput(run_fdsid({"identify-frf", "--frf", f_hz, "--frequency-unit", "hz", "--order", "4"}),
                         {"cycles/sample", "above the Nyquist frequency"}));
  EXPECT_TRUE(IsBadInput(run_fdsid({"identify-frf", "--frf", f_hz, "--domain", "continuous", "--sample-time",
                                    "0.0025", "--order", "4"}),
                         {"--sample-time", "applies to discrete-time FRFs"}));
  EXPECT_TRUE(IsBadInput(run_fdsid({"identify-frf", "--frf", f_hz, "--sample-time", "-1", "--order", "4"}),
                         {"not a positive number of seconds"}));
  simulate(64, 4, 1e-3, "rec");
  EXPECT_TRUE(IsBadInput(run_fdsid({"identify-frf", "--data", path("rec.csv"), "--meta", path("rec.meta.json"),
                                    "--frequency-unit", "hz"}),
                         {"apply to an FRF file", "meta"}));
  // A check that contradicts the candidate's units is refused, not run.
  EXPECT_TRUE(IsBadInput(run_fdsid({"check", "--model", path("m_hz.json"), "--frf", f_hz, "--frequency-unit", "rad",
                                    "--sample-time", "0.005"}),
                         {"contradict the candidate"}));
}

// Review finding 33: a known output noise level (--noise-std) identifies from
// fewer than 4 periods, even one. Tolerance as SimulatedRecordsIdentifyThePlant
// (the same first-order bound with M = 1). The fit verdict uses the known
// variance (Exp(1) terms): no misfit with the true noise level; a level 100
// times too small makes V_SUB ~1e4 times its expected value, a misfit.
TEST_F(CliFrf, AKnownNoiseLevelIdentifiesFromOnePeriod) {
  const int P = 128, M = 1, L = 32;
  const double noise = 1e-4;
  simulate(P, M, noise, "one");
  EXPECT_TRUE(IsBadInput(run_fdsid({"identify-frf", "--data", path("one.csv"), "--meta", path("one.meta.json"),
                                    "--order", "4"}),
                         {"M >= 4", "--noise-std"}));
  const RunResult r = run_fdsid({"identify-frf", "--data", path("one.csv"), "--meta", path("one.meta.json"),
                                 "--order", "4", "--r", "8", "--noise-std", "1e-4", "--json", path("k.json")});
  ASSERT_TRUE(Succeeded(r));
  const json j = read_json("k.json");
  const fdsid::StateSpace plant = pintelon_plant();
  double gmin = INFINITY;
  for (int k = 1; k < P / 2; k += 2) gmin = std::min(gmin, std::abs(G_at(plant, std::polar(1.0, 2 * M_PI * k / P))));
  const double eps_data = 5 * noise / (std::sqrt(double(M)) * std::sqrt(P / (2.0 * L)) * gmin);
  const double kappa = j["diagnostics"]["condition"].get<double>();
  const double tol = 10 * kappa * eigen_condition(plant.A) * plant.A.operatorNorm() * eps_data;
  EXPECT_LE(pole_distance(plant.A, j["poles"]), tol);
  EXPECT_EQ(j["fit"]["periods"].get<int>(), 0);  // known variance
  EXPECT_FALSE(j["fit"]["misfit"].get<bool>()) << j["fit"].dump();
  EXPECT_EQ(j["source"]["noise_std"][0].get<double>(), 1e-4);
  const RunResult low = run_fdsid({"identify-frf", "--data", path("one.csv"), "--meta", path("one.meta.json"),
                                   "--order", "4", "--r", "8", "--noise-std", "1e-6", "--json", "-"});
  ASSERT_TRUE(Succeeded(low));
  EXPECT_TRUE(json::parse(low.out)["fit"]["misfit"].get<bool>());
  // Needs records; not with --eiv; the 50-digit reference and check refuse it by name.
  EXPECT_TRUE(IsBadInput(run_fdsid({"identify-frf", "--data", path("one.csv"), "--meta", path("one.meta.json"),
                                    "--noise-std", "1e-4", "--noise-std", "1e-4", "--order", "4"}),
                         {"--noise-std", "one per output (1)"}));
  EXPECT_TRUE(IsBadInput(run_fdsid({"identify-frf", "--data", path("one.csv"), "--meta", path("one.meta.json"),
                                    "--noise-std", "1e-4", "--order", "4", "--precision", "high"}),
                         {"--noise-std", "sample variance"}));
  EXPECT_TRUE(IsBadInput(run_fdsid({"check", "--model", path("k.json"), "--data", path("one.csv"), "--meta",
                                    path("one.meta.json")}),
                         {"known noise level"}));
}

// --noise-std against the periods' scatter (record_known_noise: the
// χ²(2 F (M − 1)) law of the deviations from the period mean, two-sided 99.9 %
// interval). The std the record was simulated with: no warning (a false alarm
// has probability 1e-3 at this fixed seed's draw); a variance given for the
// std (1e-8 for 1e-4) or a std 2x too large: a warning naming the std the
// scatter implies, ~1e-4 (within its sampling spread: ν = 2 · 32 · 3 = 192
// degrees of freedom give the variance ±10 % at 1 sd, the std ±5 %; 3 sd:
// 0.85e-4 ... 1.15e-4, checked to the 2 digits printed).
TEST_F(CliFrf, AKnownNoiseLevelIsComparedWithThePeriodsScatter) {
  const int P = 128, M = 4;
  simulate(P, M, 1e-4, "four");
  const auto run = [&](const char* std) {
    return run_fdsid({"identify-frf", "--data", path("four.csv"), "--meta", path("four.meta.json"), "--order", "4",
                      "--r", "8", "--noise-std", std, "--json", "-"});
  };
  const auto disagreement = [](const RunResult& r) {
    const json j = json::parse(r.out);
    for (const auto& w : j["warnings"])
      if (w.get<std::string>().rfind("--noise-std", 0) == 0) return w.get<std::string>();
    return std::string();
  };
  const RunResult right = run("1e-4");
  ASSERT_TRUE(Succeeded(right));
  EXPECT_EQ(disagreement(right), "");
  for (const char* wrong : {"1e-8", "2e-4"}) {
    const RunResult r = run(wrong);
    ASSERT_TRUE(Succeeded(r));
    const std::string w = disagreement(r);
    ASSERT_NE(w, "") << wrong << ": " << r.out;
    EXPECT_NE(w.find("over the 4 periods"), std::string::npos) << w;
    const size_t at = w.find("a noise std of ");
    ASSERT_NE(at, std::string::npos) << w;
    const double implied = std::stod(w.substr(at + 15));
    EXPECT_GT(implied, 0.85e-4) << w;
    EXPECT_LT(implied, 1.15e-4) << w;
  }
  // One period has no scatter to compare: nothing said.
  simulate(P, 1, 1e-4, "single");
  const RunResult one = run_fdsid({"identify-frf", "--data", path("single.csv"), "--meta", path("single.meta.json"),
                                   "--order", "4", "--r", "8", "--noise-std", "1e-8", "--json", "-"});
  ASSERT_TRUE(Succeeded(one));
  EXPECT_EQ(disagreement(one), "");
}

// Review finding 29: a resonance outside the excited band. simulate-records
// names the model's (the Eq. 36 plant resonates at 2.38 rad/sample, damping
// 0.069 rad/sample; the default lines stop below P/4, at 1.55 rad/sample);
// identify-frf names an identified one (noise-free FRF on 0.02 ... 1.5
// rad/sample: the exact model, whose pair at 2.38 lies outside). Neither is
// said when the band covers the resonance.
TEST_F(CliFrf, AResonanceOutsideTheExcitedBandIsNamed) {
  const std::string model = write("plant.json", kPintelonModel);
  const RunResult narrow = run_fdsid({"simulate-records", "--model", model, "--out", path("n.csv"), "--meta-out",
                                      path("n.meta.json"), "--period", "256", "--periods", "4"});
  ASSERT_TRUE(Succeeded(narrow));
  EXPECT_NE(narrow.out.find("warning: the model's pole pair -0.677"), std::string::npos) << narrow.out;
  EXPECT_NE(narrow.out.find("above the band"), std::string::npos) << narrow.out;
  EXPECT_NE(narrow.out.find("default: odd lines below P/4"), std::string::npos) << narrow.out;
  std::vector<std::string> full = {"simulate-records", "--model", model, "--out", path("f.csv"), "--meta-out",
                                   path("f.meta.json"), "--period", "256", "--periods", "4", "--lines"};
  for (int k = 1; k < 128; k += 2) full.push_back(std::to_string(k));
  const RunResult wide = run_fdsid(full);
  ASSERT_TRUE(Succeeded(wide));
  EXPECT_EQ(wide.out.find("warning"), std::string::npos) << wide.out;

  std::vector<double> low_band;
  for (int k = 0; k < 60; ++k) low_band.push_back(0.02 + (1.5 - 0.02) * k / 59);
  const RunResult r = run_fdsid({"identify-frf", "--frf", write("low.csv", frf_csv(pintelon_plant(), low_band, 1e-8)),
                                 "--order", "4", "--r", "8", "--json", path("low.json")});
  ASSERT_TRUE(Succeeded(r));
  EXPECT_NE(r.out.find("outside the data's frequencies (0.02 to 1.5 rad/sample)"), std::string::npos) << r.out;
  const RunResult all = run_fdsid({"identify-frf", "--frf", write("all.csv", frf_csv(pintelon_plant(), discrete_grid(60), 1e-8)),
                                   "--order", "4", "--r", "8"});
  ASSERT_TRUE(Succeeded(all));
  EXPECT_EQ(all.out.find("outside"), std::string::npos) << all.out;
}

// ---------------------------------------------------------------------------
// --refine ml, --allow-unstable, --use-periods (issue 15)

// Records of the Pintelon plant with output noise: the refined model's JSON
// carries the refinement (cost no larger than the subspace estimate's, the
// sample-variance noise model of the M periods used, a fit the SML law accepts
// at level 1e-3, stable poles with standard deviations, σ of |G| per line).
TEST_F(CliFrf, RefineMlOnRecords) {
  simulate(128, 8, 1e-3, "rec");
  const RunResult r = run_fdsid({"identify-frf", "--data", path("rec.csv"), "--meta", path("rec.meta.json"), "--order",
                                 "4", "--r", "8", "--skip-periods", "1", "--use-periods", "6", "--refine", "ml",
                                 "--json", path("out.json")});
  ASSERT_TRUE(Succeeded(r)) << r.err;
  EXPECT_NE(r.out.find("refined by maximum likelihood (sample_variance)"), std::string::npos) << r.out;
  const json j = read_json("out.json");
  expect_contract_fields(j, "discrete", "pintelon2002-alg1");
  EXPECT_EQ(j["source"]["use_periods"], 6);
  EXPECT_EQ(j["source"]["periods"], 6);
  const json& f = j["refinement"];
  EXPECT_EQ(f["noise_model"], "sample_variance");
  EXPECT_LE(f["cost"].get<double>(), f["cost_subspace"].get<double>());
  EXPECT_GE(f["p_value"].get<double>(), 1e-3);
  EXPECT_EQ(f["poles"].size(), 2u);  // two pole pairs
  for (const json& p : f["poles"]) {
    EXPECT_LT(std::hypot(p["pole"][0].get<double>(), p["pole"][1].get<double>()), 1.0);
    EXPECT_GT(p["frequency_sd"].get<double>(), 0);
    EXPECT_GT(p["damping_sd"].get<double>(), 0);
  }
  EXPECT_EQ(f["magnitude_sd"].size(), 32u);  // F = 32 excited lines
  for (const json& row : j["poles"]) EXPECT_LT(std::hypot(row[0].get<double>(), row[1].get<double>()), 1.0);
}

// --max-iterations sets the refinement's iteration limit; at the limit the
// report names it and the fix once (the stopping estimate's warning and the
// iteration-limit warning said the same stop twice), and the JSON records the
// limit. Without --refine ml the option would do nothing: refused.
TEST_F(CliFrf, MaxIterationsLimitsTheRefinementAndIsNamedAtTheLimit) {
  simulate(128, 8, 1e-3, "rec");
  const std::vector<std::string> base = {"identify-frf", "--data", path("rec.csv"), "--meta", path("rec.meta.json"),
                                         "--order", "4", "--r", "8", "--skip-periods", "1", "--refine", "ml",
                                         "--json", "-"};
  std::vector<std::string> two = base;
  two.insert(two.end(), {"--max-iterations", "2"});
  const RunResult r = run_fdsid(two);
  ASSERT_TRUE(Succeeded(r)) << describe(r);
  const json j = json::parse(r.out);
  const json& f = j["refinement"];
  ASSERT_EQ(f["termination"], "no_convergence") << f.dump();
  EXPECT_EQ(f["iterations"], 2);
  EXPECT_EQ(f["max_iterations"], 2);
  const std::string w = j["warnings"].dump();
  EXPECT_NE(w.find("--max-iterations"), std::string::npos) << w;
  size_t stops = 0;
  for (const json& x : j["warnings"])
    if (x.get<std::string>().find("the refinement stopped") != std::string::npos) ++stops;
  EXPECT_EQ(stops, 1u) << w;
  const RunResult full = run_fdsid(base);
  ASSERT_TRUE(Succeeded(full));
  EXPECT_EQ(json::parse(full.out)["refinement"]["max_iterations"], 200);
  EXPECT_EQ(json::parse(full.out)["refinement"]["termination"], "convergence");
  EXPECT_TRUE(IsBadInput(run_fdsid({"identify-frf", "--data", path("rec.csv"), "--meta", path("rec.meta.json"),
                                    "--order", "4", "--max-iterations", "500"}),
                         {"--max-iterations", "--refine ml"}));
  EXPECT_TRUE(IsBadInput(run_fdsid({"identify-frf", "--data", path("rec.csv"), "--meta", path("rec.meta.json"),
                                    "--order", "4", "--refine", "ml", "--max-iterations", "0"}),
                         {"--max-iterations"}));
}

// Refused before any work: the errors-in-variables ML estimator is not there;
// --use-periods beyond what remains after the skipped periods.
TEST_F(CliFrf, RefineAndUsePeriodsRefusals) {
  simulate(64, 6, 1e-3, "rec");
  const std::string d = path("rec.csv"), m = path("rec.meta.json");
  EXPECT_TRUE(IsBadInput(run_fdsid({"identify-frf", "--data", d, "--meta", m, "--order", "4", "--improper", "--refine", "ml"}),
                         {"--refine ml", "--improper"}));
  // --eiv --refine ml: the errors-in-variables ML estimator on (U, Y) of the
  // lines the subspace estimate kept (issue 15, item 1).
  const RunResult e = run_fdsid({"identify-frf", "--data", d, "--meta", m, "--order", "4", "--r", "8", "--eiv",
                                 "--refine", "ml", "--json", path("eiv.json")});
  ASSERT_TRUE(Succeeded(e)) << describe(e);
  EXPECT_NE(e.out.find("refined by maximum likelihood (sample_variance, errors-in-variables)"), std::string::npos) << e.out;
  const json j = read_json("eiv.json");
  const json& f = j["refinement"];
  EXPECT_EQ(f["errors_in_variables"], true);
  EXPECT_LE(f["cost"].get<double>(), f["cost_subspace"].get<double>());
  // the F = 16 excited lines of P = 64, less those Eq. (34) dropped
  EXPECT_EQ(f["terms"].get<int>() + j["source"]["errors_in_variables"]["dropped_lines"].get<int>(), 16);
  EXPECT_EQ(f["magnitude_sd"].size(), static_cast<size_t>(f["terms"].get<int>()));
  EXPECT_TRUE(IsBadInput(run_fdsid({"check", "--model", path("eiv.json"), "--data", d, "--meta", m}),
                         {"field \"refinement\"", "--refine ml optimum", "without --refine"}));
  for (const json& row : j["poles"]) EXPECT_LT(std::hypot(row[0].get<double>(), row[1].get<double>()), 1.0);
  EXPECT_TRUE(IsBadInput(run_fdsid({"identify-frf", "--data", d, "--meta", m, "--skip-periods", "2", "--use-periods", "5"}),
                         {"--use-periods", "4 periods that remain"}));
}

// An FRF with an unstable pole (z = 1.25): identify-frf reflects it (z -> 1/z̄
// = 0.8) and says so, unless --allow-unstable, which keeps it with a warning.
TEST_F(CliFrf, UnstablePolesAreReflectedUnlessAllowed) {
  fdsid::StateSpace u;
  u.A = Eigen::MatrixXd::Constant(1, 1, 1.25);
  u.B = Eigen::MatrixXd::Constant(1, 1, 1.0);
  u.C = Eigen::MatrixXd::Constant(1, 1, 0.3);
  u.D = Eigen::MatrixXd::Constant(1, 1, 1.0);
  std::vector<double> omega;
  for (int k = 0; k < 40; ++k) omega.push_back(M_PI * (k + 0.5) / 40);
  const std::string f = write("g.csv", frf_csv(u, omega, 1e-8));
  const RunResult r = run_fdsid({"identify-frf", "--frf", f, "--order", "1", "--r", "3", "--json", path("s.json")});
  ASSERT_TRUE(Succeeded(r)) << r.err;
  EXPECT_NE(r.out.find("note: unstable subspace pole(s) 1.25+0j reflected"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("the identified model is unstable"), std::string::npos) << r.out;
  EXPECT_NEAR(read_json("s.json")["poles"][0][0].get<double>(), 0.8, 1e-9);
  // Review finding 1 of stop 47: the reference repeats the subspace estimate, not the reflection, so check
  // refuses the reflected model by name (it DISAGREED, unexplained) and checks the --allow-unstable one.
  EXPECT_TRUE(IsBadInput(run_fdsid({"check", "--model", path("s.json"), "--frf", f}),
                         {"field \"stabilised\"", "reflected", "--allow-unstable"}));
  const RunResult a = run_fdsid({"identify-frf", "--frf", f, "--order", "1", "--r", "3", "--allow-unstable", "--json",
                                 path("a.json")});
  ASSERT_TRUE(Succeeded(a)) << a.err;
  EXPECT_NE(a.out.find("warning: the identified model is unstable: pole 1.25+0j"), std::string::npos) << a.out;
  EXPECT_NEAR(read_json("a.json")["poles"][0][0].get<double>(), 1.25, 1e-9);
  const RunResult c = run_fdsid({"check", "--model", path("a.json"), "--frf", f}, 600);
  EXPECT_EQ(c.status, 0) << describe(c);
}

// A user review: simulate-records took --noise-std inf and --rms 1e300 (exit
// 0; the overflowed record then made identify-frf blame the file's lines) and
// refused --noise-std -0.1 without naming the option. Each is bad input naming
// its option, and no file is written.
TEST_F(CliFrf, SimulateRecordsRefusesLevelsThatAreNotFiniteOrOverflow) {
  const std::string model = write("model.json", kPintelonModel);
  const auto simulate = [&](const std::string& option, const std::string& value) {
    return run_fdsid({"simulate-records", "--model", model, "--out", path("big.csv"), "--meta-out",
                      path("big.meta.json"), "--period", "64", "--periods", "2", option, value});
  };
  for (const std::string v : {"inf", "nan", "-0.1"}) {
    EXPECT_TRUE(IsBadInput(simulate("--noise-std", v), {"--noise-std", v}));
    EXPECT_TRUE(IsBadInput(simulate("--input-noise-std", v), {"--input-noise-std", v}));
  }
  for (const std::string v : {"inf", "0", "-1"}) EXPECT_TRUE(IsBadInput(simulate("--rms", v), {"--rms", v}));
  // Finite but too large: the record's samples would pass 2^495, whose squares
  // the readers' period variances sum (cli/simulate.cpp).
  EXPECT_TRUE(IsBadInput(simulate("--rms", "1e300"), {"--rms", "beyond 2^495"}));
  EXPECT_FALSE(std::filesystem::exists(path("big.csv")));
  EXPECT_FALSE(std::filesystem::exists(path("big.meta.json")));
  // A level well inside the range is taken.
  EXPECT_TRUE(Succeeded(simulate("--rms", "1e100")));
}

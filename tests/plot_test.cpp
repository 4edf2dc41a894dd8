// Figures of --plot (plot/): what each builder puts on its panels, and that
// render() writes a complete SVG or PNG with the labels, or refuses cleanly.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "fdsid/error.hpp"
#include "fdsid/figures.hpp"
#include "fdsid/frf_id.hpp"
#include "fdsid/model.hpp"
#include "fdsid/paper.hpp"
#include "fdsid/gap.hpp"
#include "fdsid/plot.hpp"
#include "fdsid/simulate.hpp"
#include "fdsid/spectrum_id.hpp"
#include "svg_text.hpp"

namespace fs = std::filesystem;
using fdsid::plot::Figure;
using fdsid::plot::Panel;
using fdsid::plot::Series;

namespace {

struct TempDir {
  fs::path path;
  TempDir() {
    std::random_device rd;
    path = fs::temp_directory_path() / ("fdsid_plot_test_" + std::to_string(rd()));
    fs::create_directories(path);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

const Series* find_series(const Panel& p, const std::string& label) {
  for (const Series& s : p.series)
    if (s.label == label) return &s;
  return nullptr;
}

double decades(const std::vector<double>& v) {
  double lo = INFINITY, hi = 0;
  for (double x : v)
    if (x > 0) {
      lo = std::min(lo, x);
      hi = std::max(hi, x);
    }
  return std::log10(hi / lo);
}

}  // namespace

// ---------------------------------------------------------------------------
// transmission zeros (fast/ model.hpp), which the pole-zero panels draw

TEST(Zeros, FirstOrderWithFeedthrough) {
  // G(z) = 1 + 0.4/(z - 0.9) = (z - 0.5)/(z - 0.9): one zero at 0.5. The pencil
  // is 2x2 with entries O(1); QZ is backward stable, so the zero is exact to a
  // few units of roundoff: tolerance 100 u.
  fdsid::StateSpace m;
  m.A = Eigen::MatrixXd::Constant(1, 1, 0.9);
  m.B = Eigen::MatrixXd::Constant(1, 1, 1.0);
  m.C = Eigen::MatrixXd::Constant(1, 1, 0.4);
  m.D = Eigen::MatrixXd::Constant(1, 1, 1.0);
  const Eigen::VectorXcd z = fdsid::zeros(m);
  ASSERT_EQ(z.size(), 1);
  EXPECT_NEAR(z(0).real(), 0.5, 100 * 1.1e-16);
  EXPECT_NEAR(z(0).imag(), 0.0, 100 * 1.1e-16);
}

TEST(Zeros, StrictlyProperDropsInfiniteZeros) {
  // G(z) = (z - 0.3) / ((z - 0.5)(z + 0.2)) in controllable form, D = 0:
  // one finite zero at 0.3, the other pencil eigenvalues are infinite.
  // A = [0.7 -(-0.1)...]: z^2 - 0.3 z - 0.1 → A = [[0.3, 0.1], [1, 0]], B = e1,
  // C = [1, -0.3]. Tolerance as above (entries O(1)).
  fdsid::StateSpace m;
  m.A.resize(2, 2);
  m.A << 0.3, 0.1, 1.0, 0.0;
  m.B = Eigen::MatrixXd::Zero(2, 1);
  m.B(0, 0) = 1;
  m.C.resize(1, 2);
  m.C << 1.0, -0.3;
  m.D = Eigen::MatrixXd::Zero(1, 1);
  const Eigen::VectorXcd z = fdsid::zeros(m);
  ASSERT_EQ(z.size(), 1);
  EXPECT_NEAR(std::abs(z(0) - std::complex<double>(0.3, 0)), 0.0, 100 * 1.1e-16);
  // Non-square models have no transmission zeros here.
  m.C = Eigen::MatrixXd::Zero(2, 2);
  m.D = Eigen::MatrixXd::Zero(2, 1);
  EXPECT_EQ(fdsid::zeros(m).size(), 0);
}

// ---------------------------------------------------------------------------
// What the builders put on the panels

TEST(Figures, Table1ShowsTheCollapseOfSigma5BesideTheRankOfY) {
  const auto rows = fdsid::reproduce_table1();
  const Figure f = fdsid::plot::table1_figure(rows);
  ASSERT_EQ(f.panels.size(), 2u);
  const Panel &vo = f.panels[0], &ak = f.panels[1];
  EXPECT_TRUE(vo.y.log && ak.y.log);
  // One tick per M, named (review finding 44), and σ_k in one colour in both panels.
  ASSERT_EQ(vo.x.categories.size(), rows.size());
  EXPECT_EQ(vo.x.categories.front(), std::to_string(rows.front().M));
  for (int k = 1; k <= 5; ++k)
    EXPECT_EQ(find_series(vo, "#gs#d" + std::to_string(k) + "#u")->colour,
              find_series(ak, "#gs#d" + std::to_string(k) + "#u")->colour)
        << "sigma_" << k;
  const Series* s5 = find_series(vo, "#gs#d5#u");
  const Series* y8 = find_series(ak, "#gs#d8#u");
  ASSERT_NE(s5, nullptr);
  ASSERT_NE(y8, nullptr);
  ASSERT_EQ(s5->y.size(), rows.size());
  for (size_t i = 0; i < rows.size(); ++i) EXPECT_EQ(s5->y[i], rows[i].vo_sigmas(4));
  // Akçay (2011) Table 1: σ5 falls from 2.4e-3 (M = 16) to ~1e-16 (M = 512),
  // more than 10 decades; σ8 of 𝒴 (2n = 8) stays within one decade.
  EXPECT_GT(decades(s5->y), 10.0);
  EXPECT_LT(decades(y8->y), 1.0);
}

TEST(Figures, GapFigureCarriesEveryStageAndTheBands) {
  // The plant of Pintelon (2002) Eq. (36) measured with a 20 % gain error.
  const fdsid::StateSpace g = fdsid::pintelon_plant();
  fdsid::StateSpace truth = g;
  truth.B *= 1.2;
  truth.D *= 1.2;
  fdsid::RecordOptions o;
  o.period = 512;
  o.periods = 8;
  o.output_noise_std = 0.01;
  o.seed = 7;
  fdsid::RecordMeta meta;
  const Eigen::MatrixXd rec = fdsid::simulate_periodic_record(truth, o, meta);
  const fdsid::GapReport r = fdsid::diagnose_gap(g, rec, 1, meta);
  const Figure f = fdsid::plot::gap_figure(r, 8);
  ASSERT_EQ(f.panels.size(), 2u);
  const Panel& t = f.panels[0];
  EXPECT_TRUE(t.y.log);
  // Lines 1 ... 127 (the default odd lines below P/4) span two decades: a log
  // frequency axis (review finding 47).
  EXPECT_TRUE(t.x.log);
  ASSERT_GE(r.steps.size(), 2u);  // the model and at least the gain correction
  EXPECT_EQ(r.steps.front().first, "model");
  EXPECT_EQ(r.steps.back().second, r.t_after);
  for (size_t i = 0; i < r.steps.size(); ++i) EXPECT_EQ(t.series[i].y.size(), static_cast<size_t>(r.frequency.size()));
  EXPECT_EQ(t.bands.size(), r.bands.size());
  // Every candidate effect is named on the second panel's axis, best first.
  ASSERT_EQ(f.panels[1].x.categories.size(), r.candidates.size());
  for (size_t i = 0; i < r.candidates.size(); ++i) EXPECT_EQ(f.panels[1].x.categories[i], to_string(r.candidates[i].effect()));
}

// identify-frf's figure (review findings 30, 48, 49): the singular values'
// index axis has whole-number ticks, the line drawn is the order rule's
// threshold σ² = 2 × edge (not the edge), and the title names the r the order
// was read at beside the model's r when they differ.
TEST(Figures, FrfFigureDrawsTheOrderThresholdAtTheROfTheOrderPass) {
  const fdsid::StateSpace g = fdsid::pintelon_plant();
  fdsid::RecordOptions o;
  o.period = 128;
  o.periods = 6;
  o.output_noise_std = 0.01;
  o.seed = 5;
  for (int k = 1; k < 64; k += 2) o.lines.push_back(k);
  fdsid::RecordMeta meta;
  const Eigen::MatrixXd rec = fdsid::simulate_periodic_record(g, o, meta);
  const fdsid::FrfData d = fdsid::record_statistics(rec, 1, meta, fdsid::Domain::Discrete).data;
  fdsid::FrfOptions fo;  // order auto, r by V_SUB
  const fdsid::FrfResult res = fdsid::identify_frf(d, fo);
  ASSERT_GT(res.noise_edge, 0);
  const Figure f = fdsid::plot::frf_figure(d, res);
  ASSERT_EQ(f.panels.size(), 5u);  // |G|, phase (review finding 43), residual, singular values, poles
  EXPECT_EQ(f.panels[1].y.label, "phase of G (degrees)");
  const Panel& sv = f.panels[3];
  EXPECT_TRUE(sv.x.integer);
  const Series* threshold = find_series(sv, "order threshold #gs#u2#d = 2 × noise edge (Marchenko-Pastur)");
  ASSERT_NE(threshold, nullptr);
  EXPECT_DOUBLE_EQ(threshold->y.at(0), std::sqrt(2 * res.noise_edge));
  // The order rule: σ_n above the threshold, σ_{n+1} not (Pintelon 2002 Section 5 as fast/ applies it).
  EXPECT_GT(res.singular_values(res.order - 1), threshold->y[0]);
  EXPECT_LE(res.singular_values(res.order), threshold->y[0]);
  if (res.order_r != res.r)
    EXPECT_NE(sv.title.find("(r = " + std::to_string(res.order_r) + "; model: r = " + std::to_string(res.r) + ")"),
              std::string::npos)
        << sv.title;
  else
    EXPECT_NE(sv.title.find("(r = " + std::to_string(res.r) + ")"), std::string::npos) << sv.title;
}

// Review finding 7: one experiment on two inputs holds no FRF per input; the
// figure draws the model alone and the outputs' residual |Y − Ĝ U|, which is
// at the noise level for the model that generated the data.
TEST(Figures, FrfFigureOfOneExperimentOnTwoInputsDrawsNoDataFrf) {
  const fdsid::StateSpace g = fdsid::pintelon_plant();
  fdsid::FrfData d;
  d.domain = fdsid::Domain::Discrete;
  const int F = 40;
  d.omega.resize(F);
  std::mt19937_64 rng(11);
  std::normal_distribution<double> n01;
  for (int k = 0; k < F; ++k) {
    d.omega(k) = M_PI * (k + 0.5) / F;
    Eigen::MatrixXcd U(2, 1);
    U << std::polar(1.0, 6.28 * n01(rng)), std::polar(1.0, 6.28 * n01(rng));
    const std::complex<double> z = std::polar(1.0, d.omega(k));
    const std::complex<double> G1 = fdsid::transfer(g, z)(0, 0), G2 = 0.5 / (z - 0.8);
    d.U.push_back(U);
    d.Y.push_back(Eigen::MatrixXcd::Constant(1, 1, G1 * U(0, 0) + G2 * U(1, 0)));
    d.variance.push_back(Eigen::MatrixXd::Constant(1, 1, 1e-6));
  }
  fdsid::FrfResult res;  // the two-input model that generated the data: [G1 G2]
  res.order = 5;
  res.r = res.order_r = 10;
  res.model.domain = fdsid::Domain::Discrete;
  res.model.A = Eigen::MatrixXd::Zero(5, 5);
  res.model.A.topLeftCorner(4, 4) = g.A;
  res.model.A(4, 4) = 0.8;
  res.model.B = Eigen::MatrixXd::Zero(5, 2);
  res.model.B.topLeftCorner(4, 1) = g.B;
  res.model.B(4, 1) = 1;
  res.model.C = Eigen::MatrixXd::Zero(1, 5);
  res.model.C.leftCols(4) = g.C;
  res.model.C(0, 4) = 0.5;
  res.model.D = Eigen::MatrixXd::Zero(1, 2);
  res.model.D(0, 0) = g.D(0, 0);
  res.singular_values = Eigen::VectorXd::LinSpaced(10, 10, 1);
  const Figure f = fdsid::plot::frf_figure(d, res);
  const Panel &mag = f.panels[0], &resid = f.panels[2];
  EXPECT_NE(mag.title.find("no data FRF per input"), std::string::npos) << mag.title;
  for (const Series& s : mag.series) EXPECT_EQ(s.label.rfind("data", 0), std::string::npos) << s.label;
  const Series* r = find_series(resid, "output residual");
  ASSERT_NE(r, nullptr);
  ASSERT_EQ(r->y.size(), static_cast<size_t>(F));
  // Exact data: the residual is rounding, |Y| u times a few (≤ 1e-12 for |Y| ≤ 1e3).
  for (double e : r->y) EXPECT_LE(e, 1e-12);
}

// Review finding 41: the legend moves off the data. Poles in the upper right
// (a pole-zero map's positive frequencies) send it elsewhere; an empty upper
// right keeps the preferred corner.
// Review finding 41: the pole-zero legend hid the +j pole of the Silverbox's
// order-2 model (a pair near 0.70 ± 0.66j). The panel leaves room above the
// map: in the window render() draws it in (panel_window), every pole and zero
// lies below the legend's box, whose height plot.hpp states (entries × 8 % +
// 4 % of the panel).
TEST(Figures, PoleZeroLegendLeavesThePolesVisible) {
  fdsid::StateSpace m;
  m.A.resize(2, 2);
  m.A << 0.70, 0.66, -0.66, 0.70;
  m.B = Eigen::MatrixXd::Zero(2, 1);
  m.B(0, 0) = 1;
  m.C.resize(1, 2);
  m.C << 1.0, 0.2;
  m.D = Eigen::MatrixXd::Zero(1, 1);
  const Panel p = fdsid::plot::pole_zero_panel(m);
  const auto [x0, x1, y0, y1] = fdsid::plot::panel_window(p);
  int entries = 0;
  for (const Series& s : p.series) entries += s.label.empty() ? 0 : 1;
  const double legend_bottom = y1 - (0.08 * entries + 0.04) * (y1 - y0);
  int markers = 0;
  for (const Series& s : p.series) {
    if (s.symbol.empty()) continue;
    for (size_t i = 0; i < s.y.size(); ++i) {
      ++markers;
      EXPECT_LT(s.y[i], legend_bottom) << s.label << " at " << s.x[i] << " + " << s.y[i] << "j";
    }
  }
  EXPECT_GE(markers, 3);  // two poles and the zero
}

// Review finding 46: at M = 512 the identified spectrum, dashed over the
// data, hid it. Dense data are a wide line under the model's thin one, at
// least twice as wide so that the data show on both sides of the model.
TEST(Figures, DenseSpectrumDataIsAWideLineUnderTheModel) {
  const fdsid::StateSpace sys = fdsid::akcay_example_system();
  const int M = 512;
  const fdsid::SpectrumData d =
      fdsid::akcay_noisy_samples(fdsid::sample_spectrum(sys, M), M, 1e-3, fdsid::NoiseVariance::UnitComplex, 1);
  fdsid::SpectrumOptions o;
  o.order = 4;
  const Figure f = fdsid::plot::spectrum_figure(d, fdsid::identify_spectrum(d, o));
  const Panel& spec = f.panels.at(0);
  const Series* data = nullptr;
  const Series* model = nullptr;
  for (const Series& s : spec.series) {
    if (s.label.rfind("data", 0) == 0) data = &s;
    if (s.label.rfind("identified", 0) == 0) model = &s;
  }
  ASSERT_TRUE(data && model);
  EXPECT_TRUE(data->line);
  EXPECT_TRUE(model->line);
  EXPECT_FALSE(model->dashed);
  ASSERT_GT(model->width, 0.0);
  EXPECT_GE(data->width, 2 * model->width);
  // Drawn in this order: the data first, the model over it.
  EXPECT_LT(data - spec.series.data(), model - spec.series.data());
}

TEST(Figures, TheLegendTakesTheEmptiestCorner) {
  Panel p;
  Series s;
  s.line = false;
  s.x = {0.8, 0.9, 0.85, -0.9};
  s.y = {0.8, 0.9, 0.6, -0.9};  // three in the upper right, one in the lower left
  p.series = {s};
  p.legend = fdsid::plot::LegendAt::TopRight;
  const auto corner = fdsid::plot::legend_corner(p, 3, -1, 1, -1, 1);
  EXPECT_TRUE(corner == fdsid::plot::LegendAt::TopLeft || corner == fdsid::plot::LegendAt::BottomRight) << int(corner);
  p.series[0].x = {-0.9};
  p.series[0].y = {-0.9};
  EXPECT_EQ(fdsid::plot::legend_corner(p, 3, -1, 1, -1, 1), fdsid::plot::LegendAt::TopRight);
}

// Review finding 45: the failure share is a share (axis to 1.05, not 1.5),
// and the paper's Table 2 values stand beside the reproduction at the paper's
// ε (Akçay 2011 Table 2: M = 1000 ... 32000).
TEST(Figures, Table2FigureOverlaysThePapersValues) {
  fdsid::Table2Options o;
  o.epsilon = 1e-3;
  o.realizations = 2;
  fdsid::Table2Row row;
  row.M = 1000;
  row.l2 = 1e-4;
  row.linf = 5e-4;
  row.l2_all = {1e-4, 1e-4};
  row.linf_all = {5e-4, 5e-4};
  const Figure f = fdsid::plot::table2_figure({row}, o);
  const Series* paper = find_series(f.panels[0], "Akcay (2011) Table 2, L#d2#u");
  ASSERT_NE(paper, nullptr);
  ASSERT_EQ(paper->x.size(), 6u);
  EXPECT_EQ(paper->x.front(), 1000);
  EXPECT_EQ(paper->y.front(), 1.55e-4);  // Table 2, M = 1,000
  EXPECT_LE(f.panels[1].y.max, 1.05);
  o.epsilon = 1e-2;  // another ε: nothing of the paper's to compare with
  EXPECT_EQ(find_series(fdsid::plot::table2_figure({row}, o).panels[0], "Akcay (2011) Table 2, L#d2#u"), nullptr);
}

// ---------------------------------------------------------------------------
// Rendering

TEST(Render, SvgHasTheLabelsAndLegend) {
  TempDir d;
  Figure f;
  Panel p;
  p.title = "Title here";
  p.x = fdsid::plot::axis("frequency (Hz)", false);
  p.y = fdsid::plot::axis("magnitude", true);
  Series s;
  s.label = "measured";
  s.x = {1, 2, 3, 4};
  s.y = {1e-3, 1e-1, 1e1, 1e3};
  p.series = {s};
  p.bands = {{1.5, 2.5}};
  p.band_label = "flagged";
  f.panels = {p};
  const fs::path out = d.path / "a.svg";
  fdsid::plot::render(f, out.string());
  const std::string svg = slurp(out);
  ASSERT_NE(svg.find("<svg"), std::string::npos);
  const std::string text = fdsid::testing::svg_text_of(svg);
  for (const char* needle : {"frequency (Hz)", "magnitude", "Title here", "measured", "flagged"})
    EXPECT_NE(text.find(needle), std::string::npos) << needle;
  // No temporary file is left beside it.
  int files = 0;
  for (const auto& e : fs::directory_iterator(d.path)) files += e.is_regular_file();
  EXPECT_EQ(files, 1);
}

TEST(Render, PngIsAPngImage) {
  TempDir d;
  const Figure f = fdsid::plot::table1_figure(fdsid::reproduce_table1({16, 32, 64}));
  const fs::path out = d.path / "t1.PNG";  // extension case does not matter
  fdsid::plot::render(f, out.string());
  const std::string png = slurp(out);
  ASSERT_GT(png.size(), 1000u);
  EXPECT_EQ(png.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
}

TEST(Render, RefusesOtherExtensionsAndMissingDirectories) {
  TempDir d;
  Figure f;
  f.panels.resize(1);
  auto refuses = [&](const std::string& path, const std::string& why) {
    try {
      fdsid::plot::render(f, path);
      ADD_FAILURE() << path << " was accepted";
    } catch (const fdsid::Error& e) {
      EXPECT_EQ(e.kind(), fdsid::ErrorKind::Input);
      EXPECT_EQ(e.where(), "--plot");
      EXPECT_NE(e.message().find(why), std::string::npos) << e.what();
    }
  };
  refuses((d.path / "a.pdf").string(), ".svg or .png");
  refuses((d.path / "a").string(), ".svg or .png");
  refuses((d.path / "no" / "such" / "a.svg").string(), "does not exist");
  fs::create_directories(d.path / "dir.svg");
  refuses((d.path / "dir.svg").string(), "is a directory");
  f.panels.clear();
  refuses((d.path / "empty.svg").string(), "no panels");
}

TEST(Render, NonFiniteAndNonPositiveValuesAreSkippedNotDrawn) {
  // A log axis cannot show 0 or a negative value, nor any axis NaN/Inf: such
  // points break the line instead of failing the figure.
  TempDir d;
  Figure f;
  Panel p;
  p.x = fdsid::plot::axis("x", false);
  p.y = fdsid::plot::axis("y", true);
  Series s;
  s.label = "with gaps";
  s.x = {0, 1, 2, 3, 4, 5};
  s.y = {1, 0, -1, NAN, INFINITY, 10};
  p.series = {s};
  f.panels = {p};
  EXPECT_NO_THROW(fdsid::plot::render(f, (d.path / "gaps.svg").string()));
  EXPECT_TRUE(fs::exists(d.path / "gaps.svg"));
}

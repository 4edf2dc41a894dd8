// The figures of `--plot`: data of fast/'s results arranged on panels.
#include "fdsid/figures.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "fdsid/model.hpp"

namespace fdsid::plot {
namespace {

constexpr double kPi = 3.14159265358979323846;
const Colour kCycle[] = {Blue, Orange, Green, Red, Purple, Brown, Pink, Grey, Olive, Cyan};

std::vector<double> vec(const Eigen::VectorXd& v) { return std::vector<double>(v.data(), v.data() + v.size()); }

std::string num(double v, int digits = 3) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.*g", digits, v);
  return buf;
}

std::string sigma(int k) { return "#gs#d" + std::to_string(k) + "#u"; }

Series hline(const std::string& label, double x0, double x1, double y, Colour c) {
  Series s;
  s.label = label;
  s.x = {x0, x1};
  s.y = {y, y};
  s.colour = c;
  s.dashed = true;
  return s;
}

// q-quantile of the sorted finite values (linear interpolation).
double quantile(std::vector<double> v, double q) {
  v.erase(std::remove_if(v.begin(), v.end(), [](double x) { return !std::isfinite(x); }), v.end());
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const double pos = q * (v.size() - 1);
  const size_t i = static_cast<size_t>(pos);
  return i + 1 < v.size() ? v[i] + (pos - i) * (v[i + 1] - v[i]) : v[i];
}

// Singular values with the order read between σ_k and σ_{k+1} marked.
// noise_level > 0: a horizontal line there, labelled noise_label.
Panel singular_value_panel(const Eigen::VectorXd& sv, int marked, const std::string& title, const std::string& mark_label,
                           double noise_level, const std::string& noise_label = "") {
  Panel p;
  p.title = title;
  p.x = axis("index k", false);
  p.x.integer = true;
  p.y = axis("singular value #gs#dk#u", true);
  Series s;
  s.label = "#gs#dk#u";
  for (Eigen::Index i = 0; i < sv.size(); ++i) {
    s.x.push_back(static_cast<double>(i + 1));
    s.y.push_back(sv(i));
  }
  s.symbol = "•";
  s.colour = Blue;
  p.series.push_back(s);
  p.y.headroom = 2;  // decades of room for the legend
  const double top = sv.size() ? sv.maxCoeff() : 1;
  double bottom = top;
  for (Eigen::Index i = 0; i < sv.size(); ++i)
    if (sv(i) > 0) bottom = std::min(bottom, sv(i));
  if (marked > 0) {
    Series m;
    m.label = mark_label;
    m.x = {marked + 0.5, marked + 0.5};
    m.y = {bottom, top};
    m.colour = Red;
    m.dashed = true;
    p.series.push_back(m);
  }
  if (noise_level > 0) p.series.push_back(hline(noise_label, 1, std::max<double>(2, sv.size()), noise_level, Grey));
  return p;
}

}  // namespace

// Poles (×) and zeros (○) (figures.hpp). Zeros far outside the poles' scale are
// counted in the legend rather than squeezing the view.
Panel pole_zero_panel(const StateSpace& model) {
  const bool discrete = model.domain == Domain::Discrete;
  Panel p;
  p.equal_aspect = true;
  p.x = axis(discrete ? "Re z" : "Re s (rad/s)", false);
  p.y = axis(discrete ? "Im z" : "Im s (rad/s)", false);
  const Eigen::VectorXcd P = poles(model), Z = zeros(model);
  double scale = discrete ? 1.0 : 0.0;
  for (Eigen::Index i = 0; i < P.size(); ++i) scale = std::max(scale, std::abs(P(i)));
  if (scale == 0) scale = 1;
  Series ps, zs;
  ps.label = "poles";
  ps.symbol = "×";
  ps.line = false;
  ps.colour = Red;
  zs.label = "zeros";  // with the count of those not drawn (below): the title stays short (review finding 42)
  zs.symbol = "○";
  zs.line = false;
  zs.colour = Blue;
  for (Eigen::Index i = 0; i < P.size(); ++i) {
    ps.x.push_back(P(i).real());
    ps.y.push_back(P(i).imag());
  }
  int outside = 0;
  for (Eigen::Index i = 0; i < Z.size(); ++i) {
    if (std::abs(Z(i)) > 3 * scale) {
      ++outside;
      continue;
    }
    zs.x.push_back(Z(i).real());
    zs.y.push_back(Z(i).imag());
  }
  Series ref;
  ref.colour = Grey;
  ref.dashed = true;
  if (discrete) {
    ref.label = "unit circle";
    for (int i = 0; i <= 200; ++i) {
      ref.x.push_back(std::cos(2 * kPi * i / 200));
      ref.y.push_back(std::sin(2 * kPi * i / 200));
    }
  } else {
    ref.label = "imaginary axis";
    ref.x = {0, 0};
    ref.y = {-1.1 * scale, 1.1 * scale};
  }
  p.series = {ref, ps, zs};
  p.title = std::string("poles and zeros (") + (discrete ? "z" : "s") + "-plane)";
  if (outside > 0) p.series.back().label += " (" + std::to_string(outside) + " beyond 3·max|pole| not drawn)";
  p.legend = LegendAt::TopRight;
  // Room above the map for the legend (review finding 41: it hid the +j pole
  // of the Silverbox's pair): the legend box is entries × 8 % + 4 % of the
  // panel's height (plot.hpp, legend_corner), plus 3 % of margin; a headroom h
  // of the data span leaves h / (1 + h) of the height empty at the top.
  const double f = 0.08 * static_cast<double>(p.series.size()) + 0.04 + 0.03;
  p.y.headroom = f / (1 - f);
  return p;
}

namespace {

}  // namespace

Figure table1_figure(const std::vector<Table1Row>& rows) {
  Figure f;
  f.columns = 2;
  Panel vo, ak;
  vo.title = "Van Overschee (1997): G#d9#uF#d8#u (Akcay Eq. 13)";
  ak.title = "Akcay (2011): Y of Eq. (19), p = 9, r = 8";
  for (Panel* p : {&vo, &ak}) {
    p->x = axis("M (grid intervals, M + 1 samples on [0, #gp])", true);
    p->y = axis("singular value", true);
    p->legend = LegendAt::BottomLeft;
  }
  // The x axis: one tick per row, named by its M (review finding 44: a log
  // axis over 16 ... 512 labelled only 10²); M doubles from row to row, so the
  // rows are evenly spaced in log M.
  std::vector<std::string> Ms;
  for (const Table1Row& r : rows) Ms.push_back(std::to_string(r.M));
  for (Panel* p : {&vo, &ak}) {
    p->x = axis("M (grid intervals, M + 1 samples on [0, #gp])", false, 0.5, rows.size() + 0.5);
    p->x.categories = Ms;
  }
  // One colour per σ_k in both panels (finding 44: σ4 changed colour between
  // them); σ5, the one that collapses on the left, in red.
  const Colour sigma_colours[] = {Blue, Orange, Green, Purple, Red, Brown, Pink, Olive, Cyan, Black};
  auto add = [&](Panel& p, const Eigen::VectorXd Table1Row::*field, int k) {
    Series s;
    s.label = sigma(k);
    s.colour = sigma_colours[(k - 1) % 10];
    s.symbol = "•";
    for (size_t i = 0; i < rows.size(); ++i)
      if ((rows[i].*field).size() >= k) {
        s.x.push_back(i + 1.0);
        s.y.push_back((rows[i].*field)(k - 1));
      }
    p.series.push_back(s);
  };
  for (int k = 1; k <= 5; ++k) add(vo, &Table1Row::vo_sigmas, k);
  const int two_n = rows.empty() ? 0 : static_cast<int>(rows.front().akcay_sigmas.size());
  for (int k = 1; k <= two_n; ++k) add(ak, &Table1Row::akcay_sigmas, k);
  // Rounding level of a double SVD: u σ_1 with u = 2^-53.
  for (Panel* p : {&vo, &ak}) {
    Series u;
    u.label = "u·#gs#d1#u (double rounding)";
    u.colour = Grey;
    u.dashed = true;
    const Eigen::VectorXd Table1Row::*field = p == &vo ? &Table1Row::vo_sigmas : &Table1Row::akcay_sigmas;
    for (size_t i = 0; i < rows.size(); ++i)
      if ((rows[i].*field).size() > 0) {
        u.x.push_back(i + 1.0);
        u.y.push_back(std::ldexp((rows[i].*field)(0), -53));
      }
    p->series.push_back(u);
  }
  f.panels = {vo, ak};
  return f;
}

Figure table2_figure(const std::vector<Table2Row>& rows, const Table2Options& o) {
  Figure f;
  f.columns = 2;
  Panel err, fail;
  err.title = "Algorithm 1, #ge = " + num(o.epsilon) + ", " + std::to_string(o.realizations) +
              " realisations (bars: 10-90 %)";
  err.x = axis("M (grid intervals)", true);
  // Review finding 45: what the error is (absolute, the paper's measured norms)
  // and the paper's own values beside the reproduction.
  err.y = axis("error of the identified spectrum: measured L#d2#u, L#d∞#u norms of Ŝ - S (absolute)", true);
  Series l2, linf;
  l2.label = "mean L#d2#u";
  l2.symbol = "•";
  l2.colour = Blue;
  linf.label = "mean L#d∞#u";
  linf.symbol = "×";
  linf.colour = Orange;
  for (const Table2Row& r : rows) {
    if (!std::isfinite(r.l2)) continue;
    l2.x.push_back(r.M);
    l2.y.push_back(r.l2);
    l2.y_low.push_back(quantile(r.l2_all, 0.1));
    l2.y_high.push_back(quantile(r.l2_all, 0.9));
    linf.x.push_back(r.M);
    linf.y.push_back(r.linf);
    linf.y_low.push_back(quantile(r.linf_all, 0.1));
    linf.y_high.push_back(quantile(r.linf_all, 0.9));
  }
  // Akçay (2011) Table 2 (100 realisations, p = r = 50, ε = 1e-3): the
  // published means, drawn as printed.
  Series paper_l2, paper_linf;
  paper_l2.label = "Akcay (2011) Table 2, L#d2#u";
  paper_l2.symbol = "○";
  paper_l2.line = false;
  paper_l2.colour = Blue;
  paper_linf = paper_l2;
  paper_linf.label = "Akcay (2011) Table 2, L#d∞#u";
  paper_linf.colour = Orange;
  paper_linf.symbol = "□";
  const double published[6][3] = {{1000, 1.55e-4, 8.18e-4}, {2000, 4.79e-5, 2.53e-4}, {4000, 3.11e-5, 1.70e-4},
                                  {8000, 1.87e-5, 1.02e-4}, {16000, 1.37e-5, 7.50e-5}, {32000, 9.47e-6, 5.16e-5}};
  if (o.epsilon == 1e-3 && o.p == 50 && o.r == 50 && o.order == 4)  // the paper's setting
    for (const auto& row : published) {
      paper_l2.x.push_back(row[0]);
      paper_l2.y.push_back(row[1]);
      paper_linf.x.push_back(row[0]);
      paper_linf.y.push_back(row[2]);
    }
  err.series = {l2, linf};
  if (!paper_l2.x.empty()) {
    err.series.push_back(paper_l2);
    err.series.push_back(paper_linf);
  }
  fail.title = "failures: vo1997 at #ge = " + num(o.vo_epsilon) + " and Algorithm 1";
  fail.x = axis("M (grid intervals)", true);
  fail.y = axis("share of runs that failed", false, -0.02, 1.05);  // a share: 0 ... 1 (review finding 45)
  fail.legend = LegendAt::TopRight;
  Series step6, other, alg1;
  step6.label = "vo1997: failed at step 6 (no stable/antistable split)";
  step6.colour = Red;
  step6.symbol = "•";
  other.label = "vo1997: failed at another step";
  other.colour = Purple;
  other.symbol = "×";
  alg1.label = "Algorithm 1 (Akcay) at #ge = " + num(o.epsilon);
  alg1.colour = Blue;
  alg1.symbol = "○";
  for (const Table2Row& r : rows) {
    if (r.vo_runs > 0) {
      step6.x.push_back(r.M);
      step6.y.push_back(static_cast<double>(r.vo_split_failures) / r.vo_runs);
      other.x.push_back(r.M);
      other.y.push_back(static_cast<double>(r.vo_failures - r.vo_split_failures) / r.vo_runs);
    }
    alg1.x.push_back(r.M);
    alg1.y.push_back(static_cast<double>(r.failures) / std::max(1, o.realizations));
  }
  fail.series = {step6, other, alg1};
  f.panels = {err, fail};
  return f;
}

Figure std_ratio_figure(const FigureResult& r, int figure, const FigureOptions& o) {
  Figure f;
  f.columns = 2;
  const std::vector<double> x = vec(r.frequency);
  const double x0 = x.empty() ? 0 : x.front(), x1 = x.empty() ? 0.5 : x.back();
  Panel ratio;
  ratio.title = "Pintelon (2002) Fig. " + std::to_string(figure) + "b: n#da#u = " + std::to_string(o.order) +
                ", M = " + std::to_string(o.M) + ", " + std::to_string(r.runs) + " runs";
  ratio.x = axis("frequency f/f#ds#u", false);
  ratio.y = axis("std(G(#gh#d S#u)) / std(G(#gh))", false);
  Series s;
  s.label = "Monte Carlo ratio";
  s.x = x;
  s.y = vec(r.ratio);
  s.colour = Blue;
  ratio.series.push_back(s);
  if (figure == 1) {
    Series t;
    t.label = "Eq. (28)";
    t.x = x;
    t.y = vec(r.theory);
    t.colour = Orange;
    t.dashed = true;
    ratio.series.push_back(t);
  }
  ratio.series.push_back(hline("bound √((M-2)/(M-3)), Eq. (30)", x0, x1, r.bound, Red));
  ratio.series.push_back(hline("1 (no cost)", x0, x1, 1.0, Grey));
  ratio.y.headroom = 0.8;  // room above the bound for the legend
  Panel sd;
  sd.title = "standard deviations of G(e#uj#gw#d) over the runs";
  sd.x = axis("frequency f/f#ds#u", false);
  sd.y = axis("std of the estimate of G", true);
  const Eigen::VectorXd* v[3] = {&r.std_sample, &r.std_subspace, &r.std_known_alpha};
  const char* names[3] = {"sample subspace #gh#dS#u (#gs#u2#d estimated)", "subspace #gh (#gs#u2#d known)",
                          "#gb(#ga#d0#u) (true A, C)"};
  // β(α₀) needs the true A, C of order n_a: Fig. 1 only (Fig. 2's n_a = 1 has none).
  for (int e = 0; e < (figure == 1 ? 3 : 2); ++e) {
    Series q;
    q.label = names[e];
    q.x = x;
    q.y = vec(*v[e]);
    q.colour = kCycle[e];
    sd.series.push_back(q);
  }
  sd.y.headroom = 1;  // a decade of room for the legend
  sd.legend = LegendAt::TopRight;
  f.panels = {ratio, sd};
  return f;
}

Figure spectrum_figure(const SpectrumData& d, const SpectrumResult& res) {
  Figure f;
  f.columns = 2;
  const int m = d.m;
  // Data on the grid and the model on a grid 4 times as fine.
  Panel spec, resid;
  spec.title = "power spectrum: data and identified G(z)G#uT#d(1/z)";
  spec.x = axis("#gw/#gp (#gw in rad/sample)", false, 0, 1);
  spec.y = axis("S(e#uj#gw#d)" + std::string(m > 1 ? " (diagonal entries)" : ""), true);
  int non_positive = 0;
  double lo = INFINITY, hi = 0;
  for (int a = 0; a < m; ++a) {
    Series data, model;
    const std::string ij = m > 1 ? std::to_string(a + 1) + std::to_string(a + 1) : "";
    data.label = "data S" + (m > 1 ? "#d" + ij + "#u" : std::string());
    data.colour = m > 1 ? kCycle[(2 * a) % 10] : Grey;
    data.line = d.M > 200;
    data.symbol = d.M > 200 ? "" : "•";
    // Dense data as a wide line under the model's thin one: where they
    // coincide both still show (review finding 46: at M = 512 the dashed model
    // hid the data entirely).
    if (data.line) data.width = 5;
    for (int k = 0; k <= d.M; ++k) {
      const double v = d.at(a, a, k).real();
      data.x.push_back(static_cast<double>(k) / d.M);
      data.y.push_back(v);
      if (v > 0) {
        lo = std::min(lo, v);
        hi = std::max(hi, v);
      } else {
        ++non_positive;
      }
    }
    model.label = "identified" + (m > 1 ? " S#d" + ij + "#u" : std::string()) + " (n = " + std::to_string(res.order) + ")";
    model.colour = kCycle[(2 * a + 1) % 10];
    model.width = 1.2;
    const int fine = std::min(4 * d.M, 4000);
    for (int k = 0; k <= fine; ++k) {
      const double w = kPi * k / fine;
      model.x.push_back(static_cast<double>(k) / fine);
      model.y.push_back(power_spectrum(res.model, std::polar(1.0, w))(a, a).real());
    }
    spec.series.push_back(data);
    spec.series.push_back(model);
  }
  // A log axis when the data span more than a decade and at most 1 % of the
  // samples (noise near a zero of the spectrum) cannot be shown on it.
  spec.y.log = hi > 10 * lo && non_positive <= (d.M + 1) * m / 100;
  if (spec.y.log && non_positive > 0)
    spec.series.front().label += " (" + std::to_string(non_positive) + (non_positive == 1 ? " sample" : " samples") +
                                 " ≤ 0 not drawn on the log axis)";
  resid.title = "relative residual on the grid";
  resid.x = spec.x;
  resid.y = axis("||S#dk#u - Ŝ#dk#u||#dF#u / ||Ŝ#dk#u||#dF#u  (Ŝ: identified)", true);
  Series rr;
  rr.label = "";
  rr.colour = Blue;
  rr.line = d.M > 200;
  rr.symbol = d.M > 200 ? "" : "•";
  for (int k = 0; k <= d.M; ++k) {
    const Eigen::MatrixXcd Sh = power_spectrum(res.model, std::polar(1.0, kPi * k / d.M));
    Eigen::MatrixXcd Sk(m, m);
    for (int a = 0; a < m; ++a)
      for (int b = 0; b < m; ++b) Sk(a, b) = d.at(a, b, k);
    rr.x.push_back(static_cast<double>(k) / d.M);
    rr.y.push_back((Sk - Sh).norm() / Sh.norm());
  }
  resid.series.push_back(rr);
  resid.legend = LegendAt::None;
  const bool vo = res.method == Method::VanOverschee1997;
  Panel sv = singular_value_panel(
      res.singular_values, res.gap_index,
      std::string("singular values of ") + (vo ? "G#dp#uF#dr#u (Eq. 13)" : "Y (Eq. 19)") + ", p = " +
          std::to_string(res.p) + ", r = " + std::to_string(res.r),
      std::string(res.order_from_data ? "order read" : "order given") + ": gap after " + sigma(res.gap_index) +
          " (n = " + std::to_string(res.order) + ")",
      0);
  f.panels = {spec, resid, sv, pole_zero_panel(res.model)};
  return f;
}

Figure frf_figure(const FrfData& d, const FrfResult& res, const std::vector<Eigen::MatrixXd>* magnitude_sd) {
  Figure f;
  f.columns = 2;
  const bool discrete = d.domain == Domain::Discrete;
  const int F = d.frequencies();
  // Frequency in Hz (cycles/sample for discrete data with Ts = 1).
  const double hz = discrete ? 1.0 / (2 * kPi * d.sample_time) : 1.0 / (2 * kPi);
  const std::string xl = discrete && d.sample_time == 1.0 ? "frequency (cycles/sample)" : "frequency (Hz)";
  const double wmin = F ? d.omega.minCoeff() : 0, wmax = F ? d.omega.maxCoeff() : 1;
  const bool logx = wmin > 0 && wmax / wmin > 100;
  const int p = d.outputs(), mi = d.inputs();
  const int entries = std::min(p * mi, 4);
  // G on the data lines: Y U^+ (U is square for FRF files and SISO records).
  std::vector<Eigen::MatrixXcd> G(F);
  for (int k = 0; k < F; ++k) G[k] = d.Y[k] * d.U[k].completeOrthogonalDecomposition().pseudoInverse();
  auto at = [&](double w) {
    return transfer(res.model, discrete ? std::polar(1.0, w) : cplx(0, w));
  };
  // Records with fewer experiments than inputs (c < m, e.g. one multisine on
  // two inputs) hold no FRF per input: Y U⁺ is no estimate of G (review
  // finding 7). The model alone is drawn, and the residual is that of the
  // outputs, |Y − Ĝ U|, against σ_Y.
  const bool data_frf = d.columns() >= mi;
  Panel mag, resid;
  mag.title = data_frf ? "FRF: data and identified model, order " + std::to_string(res.order)
                       : "FRF of the identified model, order " + std::to_string(res.order) + " (" +
                             std::to_string(d.columns()) + " experiment(s) for " + std::to_string(mi) +
                             " inputs: no data FRF per input)";
  mag.x = axis(xl, logx);
  mag.y = axis("|G|", true);
  resid.title = data_frf ? "residual |G#ddata#u - G#dmodel#u|" : "output residual |Y - G#dmodel#u U|";
  resid.x = mag.x;
  resid.y = axis(data_frf ? "|G#ddata#u - G#dmodel#u|" : "|Y - G#dmodel#u U|", true);
  // The phase panel (review finding 43: a Bode plot; |G| alone hides a delay
  // and a phase misfit): the model's phase unwrapped along the dense grid,
  // each data point on the model's branch at its frequency (model phase there
  // plus arg(G_data / G_model)).
  Panel phase;
  phase.title = "phase";
  phase.x = mag.x;
  phase.y = axis("phase of G (degrees)", false);
  const int fine = 2000;
  std::vector<double> grid(fine + 1);
  for (int q = 0; q <= fine; ++q)
    grid[q] = logx ? wmin * std::pow(wmax / wmin, static_cast<double>(q) / fine) : wmin + (wmax - wmin) * q / fine;
  auto nearest = [&](double w) {
    if (!(wmax > wmin)) return 0;
    const double t = logx ? std::log(w / wmin) / std::log(wmax / wmin) : (w - wmin) / (wmax - wmin);
    return std::clamp(static_cast<int>(std::lround(t * fine)), 0, fine);
  };
  auto wrap = [](double a) { return a - 2 * kPi * std::round(a / (2 * kPi)); };
  const double deg = 180 / kPi;
  for (int e = 0; e < entries; ++e) {
    const int i = e / mi, j = e % mi;
    const std::string ij = p * mi > 1 ? " #d" + std::to_string(i + 1) + std::to_string(j + 1) + "#u" : "";
    Series data, model, r, data_phase, model_phase;
    data.label = "data" + ij;
    data.colour = kCycle[(2 * e) % 10];
    data.line = false;
    data.symbol = "•";
    r = data;
    r.label = "residual" + ij;
    model.label = "identified" + ij;
    model.colour = kCycle[(2 * e + 1) % 10];
    std::vector<double> unwrapped(fine + 1);
    std::vector<cplx> on_grid(fine + 1);  // G of the model on the dense grid, kept for the data's branches
    for (int q = 0; q <= fine; ++q) {
      on_grid[q] = at(grid[q])(i, j);
      model.x.push_back(grid[q] * hz);
      model.y.push_back(std::abs(on_grid[q]));
      unwrapped[q] = q == 0 ? std::arg(on_grid[q]) : unwrapped[q - 1] + std::arg(on_grid[q] / on_grid[q - 1]);
    }
    model_phase = model;
    model_phase.y.clear();
    for (double a : unwrapped) model_phase.y.push_back(a * deg);
    data_phase = data;
    for (int k = 0; k < F; ++k) {
      const cplx gm = at(d.omega(k))(i, j);
      data.x.push_back(d.omega(k) * hz);
      data.y.push_back(std::abs(G[k](i, j)));
      r.x.push_back(d.omega(k) * hz);
      r.y.push_back(std::abs(G[k](i, j) - gm));
      const int q = nearest(d.omega(k));
      const double branch = unwrapped[q] + wrap(std::arg(gm) - std::arg(on_grid[q]));
      data_phase.x.push_back(d.omega(k) * hz);
      data_phase.y.push_back((branch + std::arg(G[k](i, j) / gm)) * deg);
    }
    if (data_frf) {
      mag.series.push_back(data);
      resid.series.push_back(r);
      phase.series.push_back(data_phase);
    }
    mag.series.push_back(model);
    phase.series.push_back(model_phase);
    // The refined model's uncertainty (issue 15): 2 σ of |G_model| from the
    // Cramér–Rao bound, on the residual panel, where it compares with the
    // residual and the noise (on |G| itself it is too thin to see).
    if (magnitude_sd && static_cast<int>(magnitude_sd->size()) == F) {
      Series band;
      band.label = "2#gs of |G#dmodel#u| (Cramer-Rao)" + ij;
      band.colour = model.colour;
      band.width = 3;
      band.x = r.x;
      for (int k = 0; k < F; ++k) band.y.push_back(2 * (*magnitude_sd)[k](i, j));
      resid.series.push_back(band);
    }
  }
  for (int i = 0; !data_frf && i < p; ++i) {
    Series r, sd;
    const std::string out_i = p > 1 ? " #d" + std::to_string(i + 1) + "#u" : "";
    r.label = "output residual" + out_i;
    r.colour = kCycle[(2 * i) % 10];
    r.line = false;
    r.symbol = "•";
    sd.label = "noise std #gs#dY#u" + out_i;
    sd.colour = Grey;
    sd.dashed = true;
    for (int k = 0; k < F; ++k) {
      const Eigen::MatrixXcd E = d.Y[k] - at(d.omega(k)) * d.U[k];
      for (int c = 0; c < d.columns(); ++c) {
        r.x.push_back(d.omega(k) * hz);
        r.y.push_back(std::abs(E(i, c)));
      }
      sd.x.push_back(d.omega(k) * hz);
      sd.y.push_back(std::sqrt(d.variance[k](i, 0)));
    }
    resid.series.push_back(r);
    if (d.has_noise_model) resid.series.push_back(sd);
  }
  if (p == 1 && mi == 1 && d.has_noise_model) {
    // Standard deviation of the data's G: σ_Y / |U| (σ²_Y is that of Ŷ).
    Series sd;
    sd.label = "noise std #gs#dY#u/|U|";
    sd.colour = Grey;
    sd.dashed = true;
    for (int k = 0; k < F; ++k) {
      sd.x.push_back(d.omega(k) * hz);
      sd.y.push_back(std::sqrt(d.variance[k](0, 0)) / std::abs(d.U[k](0, 0)));
    }
    resid.series.push_back(sd);
    mag.series.push_back(sd);
  }
  if (p * mi > entries) mag.title += " (first 4 entries)";
  mag.legend = LegendAt::BottomLeft;
  resid.legend = LegendAt::BottomLeft;
  // The r the order was read at, and the model's r when they differ (review
  // finding 30); the line drawn is the order rule's threshold σ² = 2 × the
  // Marchenko–Pastur edge (finding 48: the edge itself was drawn, labelled as
  // if it were the threshold).
  const std::string at_r = res.order_r == res.r ? "r = " + std::to_string(res.r)
                                                : "r = " + std::to_string(res.order_r) + "; model: r = " +
                                                      std::to_string(res.r);
  Panel sv = singular_value_panel(res.singular_values, res.order, "singular values of step 1c (" + at_r + ")",
                                  "order n = " + std::to_string(res.order), std::sqrt(2 * res.noise_edge),
                                  "order threshold #gs#u2#d = 2 × noise edge (Marchenko-Pastur)");
  phase.legend = LegendAt::BottomLeft;
  f.panels = {mag, phase, resid, sv, pole_zero_panel(res.model)};
  return f;
}

Figure gap_figure(const GapReport& r, int periods) {
  Figure f;
  f.columns = 1;
  const std::vector<double> x = vec(r.frequency);
  const double x0 = x.empty() ? 0 : x.front(), x1 = x.empty() ? 1 : x.back();
  Panel t;
  t.title = "normalised residual per excited line: t(k) ~ F(2, 2M-2) under a right model, M = " +
            std::to_string(periods);
  // Log frequency when the lines span two decades or more (review finding 47:
  // a circuit's action squeezed into 0-200 Hz of 1250); two decades of
  // headroom give the legend an empty corner.
  t.x = axis("frequency (Hz; cycles/sample when T#ds#u = 1)", x0 > 0 && x1 >= 100 * x0);
  t.y = axis("t(k) = M |Ē(k)|² / s²(k)", true);
  t.y.headroom = 2;
  for (size_t i = 0; i < r.steps.size(); ++i) {
    Series s;
    s.label = r.steps[i].first == "model" ? "model as given (gap " + num(r.gap_before) + ")" : r.steps[i].first;
    if (i + 1 == r.steps.size() && i > 0) s.label += " (gap " + num(r.gap_after) + ")";
    s.x = x;
    s.y = vec(r.steps[i].second);
    s.colour = i == 0 ? Grey : kCycle[i % 10];
    t.series.push_back(s);
  }
  t.series.push_back(hline("noise floor E t = 1", x0, x1, 1.0, Black));
  // Per-line critical value of F(2, d), d = 2M − 2: the survival function is
  // (1 + 2x/d)^(−d/2) in closed form, so x_α = (d/2)(α^(−2/d) − 1).
  const double dof = 2.0 * periods - 2, a = r.options.alpha;
  t.series.push_back(hline(num(100 * (1 - a)) + " % quantile of F(2, 2M-2) (the " + num(100 * a) +
                               " % critical value of one line)",
                           x0, x1, dof / 2 * (std::pow(a, -2 / dof) - 1), Red));
  for (const auto& b : r.bands) t.bands.push_back({b[0], b[1], ShadeRed});
  t.band_label = "flagged (Benjamini-Hochberg, FDR " + num(r.options.fdr) + ")";
  t.legend = LegendAt::TopRight;

  Panel c;
  std::string chosen;
  for (Effect e : r.present) chosen += (chosen.empty() ? "" : ", ") + std::string(to_string(e));
  c.title = "gap left by each candidate effect alone; chosen: " + (chosen.empty() ? std::string("none") : chosen);
  c.x = axis("candidate effect", false, 0.5, static_cast<double>(r.candidates.size()) + 0.5);
  c.y = axis("gap = (M-2)/(M-1) mean t", true);
  Series pts;
  pts.label = "gap with the effect added";
  pts.line = false;
  pts.symbol = "•";
  pts.colour = Blue;
  for (size_t i = 0; i < r.candidates.size(); ++i) {
    c.x.categories.push_back(to_string(r.candidates[i].effect()));
    pts.x.push_back(i + 1.0);
    pts.y.push_back(r.candidates[i].gap_after);
  }
  c.series.push_back(pts);
  const double cx0 = 0.5, cx1 = r.candidates.size() + 0.5;
  c.series.push_back(hline("model as given", cx0, cx1, r.gap_before, Grey));
  c.series.push_back(hline("noise floor (gap 1)", cx0, cx1, 1.0, Black));
  c.legend = LegendAt::BottomRight;
  f.panels = {t, c};
  return f;
}

}  // namespace fdsid::plot

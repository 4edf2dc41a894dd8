// Rendering of fdsid::plot::Figure with PLplot's C++ API (plstream).
#include "fdsid/plot.hpp"

#include <plstream.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>

#include "fdsid/error.hpp"

namespace fdsid::plot {
namespace {

constexpr double kCharScale = 0.85;  // of PLplot's default character height
constexpr double kLineWidth = 1.6;    // of a series's line, unless Series::width says otherwise

std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

// PLplot reports a fatal error through plexit(), which ends the process; the
// handler turns that into fdsid's exit status 2 with one line.
int plplot_exit_handler(const char* message) {
  std::fprintf(stderr, "fdsid: plot: PLplot failed: %s\n", message ? message : "(no message)");
  std::fflush(stderr);
  return 2;
}

// Data → PLplot world coordinates (log10 on a log axis); NaN when the point
// cannot be drawn there.
double to_world(double v, bool log) {
  if (!std::isfinite(v)) return std::numeric_limits<double>::quiet_NaN();
  if (!log) return v;
  return v > 0 ? std::log10(v) : std::numeric_limits<double>::quiet_NaN();
}

struct Range {
  double lo = std::numeric_limits<double>::infinity(), hi = -std::numeric_limits<double>::infinity();
  void add(double w) {
    if (std::isfinite(w)) {
      lo = std::min(lo, w);
      hi = std::max(hi, w);
    }
  }
};

// The window of one axis in world coordinates: the fixed range when given,
// else the data's, padded by 4 % (of the log10 span on a log axis) or, on a
// log axis spanning more than 3 decades, widened to whole decades; then
// a.headroom added above.
std::pair<double, double> data_window(const Axis& a, Range r) {
  if (!(r.lo <= r.hi)) return {a.log ? -1.0 : 0.0, 1.0};
  if (r.hi - r.lo < 1e-12 * std::max(1.0, std::abs(r.hi))) {
    const double d = a.log ? 0.5 : std::max(1e-3, 0.1 * std::abs(r.hi));
    return {r.lo - d, r.hi + d};
  }
  if (a.log && r.hi - r.lo < 1.0) {  // at least one decade: a labelled power of ten in view
    const double mid = 0.5 * (r.lo + r.hi);
    return {mid - 0.5, mid + 0.5};
  }
  if (a.log && r.hi - r.lo > 3.0) return {std::floor(r.lo - 0.05), std::ceil(r.hi + 0.05)};
  const double pad = 0.04 * (r.hi - r.lo);
  return {r.lo - pad, r.hi + pad};
}

std::pair<double, double> window(const Axis& a, const Range& r) {
  if (a.min < a.max) return {to_world(a.min, a.log), to_world(a.max, a.log)};
  auto [lo, hi] = data_window(a, r);
  hi += a.log ? a.headroom : a.headroom * (hi - lo);
  return {lo, hi};
}

// A log axis spanning more than 6 decades gets a major tick every k-th decade
// (PLplot's own log labelling writes every decade, which then overlap), drawn
// as a linear axis in log10 units with "10^v" labels and a minor tick per
// decade; shorter spans use PLplot's log axis. Returns k, or 0 for the latter.
int decade_step(const Axis& a, double lo, double hi) {
  if (!a.log || hi - lo <= 6) return 0;
  return static_cast<int>(std::ceil((hi - lo) / 6));
}

// Custom tick labels: powers of ten on a log axis drawn in log10 units, and
// category names at the integer ticks 1 … n of a category axis.
struct TickLabels {
  const std::vector<std::string>* categories = nullptr;  // of the x axis
};

void tick_label(PLINT axis, PLFLT value, char* label, PLINT length, PLPointer data) {
  const auto* t = static_cast<const TickLabels*>(data);
  if (axis == PL_X_AXIS && t->categories && !t->categories->empty()) {
    const long i = std::lround(value);
    const bool named = std::abs(value - i) < 1e-6 && i >= 1 && i <= static_cast<long>(t->categories->size());
    std::snprintf(label, static_cast<size_t>(length), "%s", named ? (*t->categories)[i - 1].c_str() : "");
    return;
  }
  std::snprintf(label, static_cast<size_t>(length), "10#u%d#d", static_cast<int>(std::lround(value)));
}

void draw_series(plstream& pls, const Series& s, const Panel& p) {
  const size_t n = std::min(s.x.size(), s.y.size());
  std::vector<PLFLT> wx(n), wy(n);
  for (size_t i = 0; i < n; ++i) {
    wx[i] = to_world(s.x[i], p.x.log);
    wy[i] = to_world(s.y[i], p.y.log);
  }
  pls.col0(s.colour);
  pls.lsty(s.dashed ? 2 : 1);
  pls.width(s.width > 0 ? s.width : kLineWidth);
  if (s.line) {
    // Polylines between the points that can be drawn.
    size_t i = 0;
    while (i < n) {
      while (i < n && !(std::isfinite(wx[i]) && std::isfinite(wy[i]))) ++i;
      size_t j = i;
      while (j < n && std::isfinite(wx[j]) && std::isfinite(wy[j])) ++j;
      if (j - i >= 2) pls.line(static_cast<PLINT>(j - i), &wx[i], &wy[i]);
      i = j;
    }
  }
  pls.lsty(1);
  pls.width(kLineWidth);
  if (!s.y_low.empty() && s.y_low.size() == n && s.y_high.size() == n) {
    for (size_t i = 0; i < n; ++i) {
      PLFLT x = wx[i], lo = to_world(s.y_low[i], p.y.log), hi = to_world(s.y_high[i], p.y.log);
      if (!std::isfinite(lo) && std::isfinite(hi)) lo = wy[i];  // lower end below zero on a log axis
      if (std::isfinite(x) && std::isfinite(lo) && std::isfinite(hi)) pls.erry(1, &x, &lo, &hi);
    }
  }
  if (!s.symbol.empty()) {
    std::vector<PLFLT> px, py;
    for (size_t i = 0; i < n; ++i)
      if (std::isfinite(wx[i]) && std::isfinite(wy[i])) {
        px.push_back(wx[i]);
        py.push_back(wy[i]);
      }
    pls.schr(0, 1.2);
    if (!px.empty()) pls.string(static_cast<PLINT>(px.size()), px.data(), py.data(), s.symbol.c_str());
    pls.schr(0, kCharScale);
  }
}

// The corner for the legend (review finding 41: legends covered poles, the
// gap's curves and a spectral peak): the panel's preferred corner unless
// another holds fewer of the data. Each corner is a box the legend's size,
// roughly: 10 % + 0.65 % per character of the longest label (at most 90 %)
// of the width, entries × 8 % + 4 % (at most 70 %) of the height; points are counted there, and along a drawn line the segments'
// midpoints too (a line crossing a corner counts). A marker (a pole, a data
// point) weighs 20 line points: a dense reference curve such as the unit
// circle must not outvote the few points a reader looks for. Ties keep the
// preference.
LegendAt emptiest_corner_impl(const Panel& p, int entries, double x0, double x1, double y0, double y1) {
  if (p.legend == LegendAt::None) return LegendAt::None;
  size_t longest = 0;  // the legend's width follows its longest label (~0.65 % of the panel per character)
  for (const Series& s : p.series) longest = std::max(longest, s.label.size());
  longest = std::max(longest, p.band_label.size());
  const double bw = std::min(0.9, 0.1 + 0.0065 * static_cast<double>(longest)) * (x1 - x0);
  const double bh = std::min(0.7, 0.08 * entries + 0.04) * (y1 - y0);
  const LegendAt corners[4] = {LegendAt::TopRight, LegendAt::TopLeft, LegendAt::BottomRight, LegendAt::BottomLeft};
  auto inside = [&](LegendAt c, double x, double y) {
    const bool right = c == LegendAt::TopRight || c == LegendAt::BottomRight;
    const bool top = c == LegendAt::TopRight || c == LegendAt::TopLeft;
    return (right ? x >= x1 - bw : x <= x0 + bw) && (top ? y >= y1 - bh : y <= y0 + bh);
  };
  int counts[4] = {0, 0, 0, 0};
  for (const Series& s : p.series) {
    const size_t n = std::min(s.x.size(), s.y.size());
    double px = NAN, py = NAN;
    for (size_t i = 0; i < n; ++i) {
      const double x = to_world(s.x[i], p.x.log), y = to_world(s.y[i], p.y.log);
      if (!std::isfinite(x) || !std::isfinite(y)) {
        px = py = NAN;
        continue;
      }
      const int weight = s.symbol.empty() ? 1 : 20;
      for (int c = 0; c < 4; ++c) {
        if (inside(corners[c], x, y)) counts[c] += weight;
        if (s.line && std::isfinite(px) && inside(corners[c], 0.5 * (x + px), 0.5 * (y + py))) ++counts[c];
      }
      px = x;
      py = y;
    }
  }
  int best = 0;
  for (int c = 0; c < 4; ++c)
    if (corners[c] == p.legend) best = c;
  for (int c = 0; c < 4; ++c)
    if (counts[c] < counts[best]) best = c;
  return corners[best];
}

void draw_legend(plstream& pls, const Panel& p, double x0, double x1, double y0, double y1) {
  if (p.legend == LegendAt::None) return;
  std::vector<const Series*> entries;
  for (const Series& s : p.series)
    if (!s.label.empty()) entries.push_back(&s);
  const bool band = !p.band_label.empty() && !p.bands.empty();
  const int n = static_cast<int>(entries.size()) + (band ? 1 : 0);
  if (n == 0) return;
  std::vector<PLINT> opt(n), text_colors(n, Black), box_colors(n, 0), box_patterns(n, 0), line_colors(n, 0),
      line_styles(n, 1), symbol_colors(n, 0), symbol_numbers(n, 1);
  std::vector<PLFLT> box_scales(n, 0.8), box_widths(n, 1.0), line_widths(n, 1.5), symbol_scales(n, 1.0);
  std::vector<const char*> text(n), symbols(n, "");
  for (int i = 0; i < static_cast<int>(entries.size()); ++i) {
    const Series& s = *entries[i];
    opt[i] = (s.line ? PL_LEGEND_LINE : 0) | (s.symbol.empty() ? 0 : PL_LEGEND_SYMBOL);
    if (opt[i] == 0) opt[i] = PL_LEGEND_NONE;
    text[i] = s.label.c_str();
    line_colors[i] = s.colour;
    line_styles[i] = s.dashed ? 2 : 1;
    if (s.width > 0) line_widths[i] = s.width;
    symbol_colors[i] = s.colour;
    symbols[i] = s.symbol.c_str();
  }
  if (band) {
    opt[n - 1] = PL_LEGEND_COLOR_BOX;
    text[n - 1] = p.band_label.c_str();
    box_colors[n - 1] = p.bands.front().colour;
  }
  PLINT position = PL_POSITION_INSIDE;
  switch (emptiest_corner_impl(p, n, x0, x1, y0, y1)) {
    case LegendAt::TopRight: position |= PL_POSITION_TOP | PL_POSITION_RIGHT; break;
    case LegendAt::TopLeft: position |= PL_POSITION_TOP | PL_POSITION_LEFT; break;
    case LegendAt::BottomRight: position |= PL_POSITION_BOTTOM | PL_POSITION_RIGHT; break;
    case LegendAt::BottomLeft: position |= PL_POSITION_BOTTOM | PL_POSITION_LEFT; break;
    case LegendAt::None: break;
  }
  PLFLT w = 0, h = 0;
  pls.legend(&w, &h, PL_LEGEND_BACKGROUND | PL_LEGEND_BOUNDING_BOX, position, 0.02, 0.02, 0.08, 0, Black, 1, 0, 0, n,
             opt.data(), 0.8, 0.75, 1.8, 0.0, text_colors.data(), text.data(), box_colors.data(), box_patterns.data(),
             box_scales.data(), box_widths.data(), line_colors.data(), line_styles.data(), line_widths.data(),
             symbol_colors.data(), symbol_scales.data(), symbol_numbers.data(), symbols.data());
}

void draw_panel(plstream& pls, const Panel& p) {
  const auto [x0, x1, y0, y1] = panel_window(p);
  if (p.equal_aspect) {
    pls.vpas(0.15, 0.95, 0.14, 0.88, 1.0);
  } else {
    pls.vpor(0.15, 0.97, 0.14, 0.88);
  }
  pls.wind(x0, x1, y0, y1);
  for (const Band& b : p.bands) {
    double a = to_world(b.x0, p.x.log), c = to_world(b.x1, p.x.log);
    if (!std::isfinite(a) || !std::isfinite(c)) continue;
    if (c - a < 2e-3 * (x1 - x0)) {  // a single flagged line stays visible
      const double mid = 0.5 * (a + c);
      a = mid - 1e-3 * (x1 - x0);
      c = mid + 1e-3 * (x1 - x0);
    }
    PLFLT bx[4] = {std::max(a, x0), std::min(c, x1), std::min(c, x1), std::max(a, x0)};
    PLFLT by[4] = {y0, y0, y1, y1};
    pls.col0(b.colour);
    pls.fill(4, bx, by);
    // A strong strip along the bottom marks the band too, so its shading can
    // stay pale: when most of the axis is flagged the curves must not drown
    // in it (review finding 47).
    const double strip = y0 + 0.03 * (y1 - y0);
    PLFLT sy[4] = {y0, y0, strip, strip};
    pls.col0(b.colour == ShadeRed ? Red : Grey);
    pls.fill(4, bx, sy);
  }
  pls.width(kLineWidth);
  for (const Series& s : p.series) draw_series(pls, s, p);
  pls.width(1.0);
  pls.col0(Black);
  pls.lsty(1);
  const bool named = !p.x.categories.empty();
  const int kx = named ? 1 : decade_step(p.x, x0, x1), ky = decade_step(p.y, y0, y1);
  const std::string xopt = std::string("bcnst") + (kx ? "o" : p.x.log ? "l" : "");
  const std::string yopt = std::string("bcnstv") + (ky ? "o" : p.y.log ? "l" : "");
  TickLabels labels{&p.x.categories};
  pls.slabelfunc(tick_label, &labels);
  if (named) pls.schr(0, 0.7 * kCharScale);  // category names are long
  // Whole-number ticks on an index axis: a step of ⌈span/8⌉ (at most ~8 labels).
  const double integer_step = p.x.integer && !p.x.log && !named ? std::max(1.0, std::ceil((x1 - x0) / 8)) : 0;
  if (integer_step > 0)
    pls.box(xopt.c_str(), integer_step, 1, "", 0, 0);
  else
    pls.box(xopt.c_str(), kx, named ? 1 : kx, "", 0, 0);
  pls.schr(0, kCharScale);
  pls.box("", 0, 0, yopt.c_str(), ky, ky);
  pls.slabelfunc(nullptr, nullptr);
  pls.lab(p.x.label.c_str(), "", p.title.c_str());
  pls.mtex("l", 4.6, 0.5, 0.5, p.y.label.c_str());
  for (const Text& t : p.texts) {
    const double tx = to_world(t.x, p.x.log), ty = to_world(t.y, p.y.log);
    if (!std::isfinite(tx) || !std::isfinite(ty)) continue;
    pls.col0(t.colour);
    pls.ptex(tx, ty, t.vertical ? 0 : 1, t.vertical ? 1 : 0, 0, t.text.c_str());
  }
  pls.col0(Black);
  draw_legend(pls, p, x0, x1, y0, y1);
}

}  // namespace

LegendAt legend_corner(const Panel& p, int entries, double x0, double x1, double y0, double y1) {
  return emptiest_corner_impl(p, entries, x0, x1, y0, y1);
}

void check_plot_path(const std::string& path) {
  const std::string ext = lower_extension(path);
  if (ext != ".svg" && ext != ".png")
    throw Error(ErrorKind::Input, "--plot", "\"" + path + "\" must end in .svg or .png (the format is read from it)");
}

std::array<double, 4> panel_window(const Panel& p) {
  Range rx, ry;
  for (const Series& s : p.series) {
    for (double v : s.x) rx.add(to_world(v, p.x.log));
    for (double v : s.y) ry.add(to_world(v, p.y.log));
    for (double v : s.y_high) ry.add(to_world(v, p.y.log));
  }
  auto [x0, x1] = window(p.x, rx);
  auto [y0, y1] = window(p.y, ry);
  if (p.equal_aspect) {
    // Square data ranges on a square viewport.
    const double cx = 0.5 * (x0 + x1), cy = 0.5 * (y0 + y1);
    const double half = 0.5 * std::max(x1 - x0, y1 - y0);
    x0 = cx - half;
    x1 = cx + half;
    y0 = cy - half;
    y1 = cy + half;
  }
  return {x0, x1, y0, y1};
}

void render(const Figure& fig, const std::string& path) {
  check_plot_path(path);
  if (fig.panels.empty()) throw Error(ErrorKind::Input, "--plot", "the figure has no panels");
  namespace fs = std::filesystem;
  const fs::path target(path);
  const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
  std::error_code ec;
  if (!fs::is_directory(dir, ec))
    throw Error(ErrorKind::Input, "--plot", "directory \"" + dir.string() + "\" of \"" + path + "\" does not exist");
  if (fs::is_directory(target, ec)) throw Error(ErrorKind::Input, "--plot", "\"" + path + "\" is a directory");
  // Temporary name in the same directory (same file system: rename is atomic).
  std::random_device rd;
  const fs::path tmp = dir / ("." + target.filename().string() + ".tmp" + std::to_string(rd() % 1000000));
  {
    std::ofstream probe(tmp);
    if (!probe) throw Error(ErrorKind::Input, "--plot", "cannot write in \"" + dir.string() + "\"");
  }
  const bool svg = lower_extension(path) == ".svg";
  const int rows = (static_cast<int>(fig.panels.size()) + fig.columns - 1) / fig.columns;
  const int height = fig.height > 0 ? fig.height : 420 * rows;
  {
    plsexit(plplot_exit_handler);
    plstream pls;
    pls.sdev(svg ? "svg" : "pngcairo");
    pls.sfnam(tmp.c_str());
    pls.spage(0, 0, fig.width, height, 0, 0);
    // cmap0: white background, black axes, then the Colour palette.
    const PLINT r[] = {255, 0, 31, 255, 44, 214, 148, 140, 227, 127, 188, 23, 225, 255};
    const PLINT g[] = {255, 0, 119, 127, 160, 39, 103, 86, 119, 127, 189, 190, 225, 234};
    const PLINT b[] = {255, 0, 180, 14, 44, 40, 189, 75, 194, 127, 34, 207, 225, 234};
    pls.scmap0(r, g, b, static_cast<PLINT>(std::size(r)));
    pls.init();
    pls.ssub(fig.columns, rows);
    pls.schr(0, kCharScale);
    for (size_t i = 0; i < fig.panels.size(); ++i) {
      pls.adv(static_cast<PLINT>(i + 1));
      draw_panel(pls, fig.panels[i]);
    }
  }  // ~plstream ends the stream and closes the file
  fs::rename(tmp, target, ec);
  if (ec) {
    fs::remove(tmp, ec);
    throw Error(ErrorKind::Input, "--plot", "cannot write \"" + path + "\"");
  }
}

}  // namespace fdsid::plot

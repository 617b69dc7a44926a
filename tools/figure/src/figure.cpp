// Lays a Figure out once in pixels and paints it through one of two painters: OpenCV (PNG) or an
// SVG text writer. Layout: a title band; panels side by side, each a square data area with metre
// ticks, a grid and its own title; the legend (and colour bar) in a column right of the panels, so
// it never hides data.
#include "whiskeye/figure/figure.h"

#include "whiskeye/figure/png_file.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <memory>
#include <sstream>
#include <stdexcept>

namespace whiskeye::figure {

// ---- FigurePanel ----

void FigurePanel::polyline(std::vector<Xy> pts, Rgb colour, double width_px, std::string cls, std::string name) {
  if (pts.size() < 2) return;
  items_.push_back({FigureItem::Kind::Polyline, std::move(pts), colour, width_px, false, 0.0, "", 0, std::move(cls),
                    std::move(name)});
}

void FigurePanel::polygon(std::vector<Xy> pts, Rgb fill, std::string cls, std::string name) {
  if (pts.size() < 3) return;
  items_.push_back({FigureItem::Kind::Polygon, std::move(pts), fill, 0.0, true, 0.0, "", 0, std::move(cls), std::move(name)});
}

void FigurePanel::disc(Xy centre, double radius_m, Rgb fill, std::string cls, std::string name) {
  items_.push_back({FigureItem::Kind::Disc, {centre}, fill, radius_m, true, 0.0, "", 0, std::move(cls), std::move(name)});
}

void FigurePanel::marker(Xy at, double radius_px, Rgb colour, bool filled, std::string cls) {
  items_.push_back({FigureItem::Kind::Marker, {at}, colour, radius_px, filled, 0.0, "", 0, std::move(cls), ""});
}

void FigurePanel::tick(Xy at, double angle, double length_px, Rgb colour, std::string cls) {
  items_.push_back({FigureItem::Kind::Tick, {at}, colour, length_px, false, angle, "", 0, std::move(cls), ""});
}

void FigurePanel::text(Xy at, std::string text, Rgb colour, double size_px, std::string cls, int anchor) {
  items_.push_back({FigureItem::Kind::Text, {at}, colour, size_px, true, 0.0, std::move(text), anchor, std::move(cls), ""});
}

void FigurePanel::include(Xy p) { extra_.push_back(p); }

bool FigurePanel::extent(double& x0, double& x1, double& y0, double& y1) const {
  x0 = y0 = std::numeric_limits<double>::infinity();
  x1 = y1 = -std::numeric_limits<double>::infinity();
  const auto add = [&](double x, double y, double r) {
    x0 = std::min(x0, x - r);
    x1 = std::max(x1, x + r);
    y0 = std::min(y0, y - r);
    y1 = std::max(y1, y + r);
  };
  for (const FigureItem& it : items_) {
    if (it.kind == FigureItem::Kind::Text) continue;  // labels follow the data, they do not size it
    for (const Xy& p : it.points) add(p.x, p.y, it.kind == FigureItem::Kind::Disc ? it.size : 0.0);
  }
  for (const Xy& p : extra_) add(p.x, p.y, 0.0);
  return std::isfinite(x0);
}

Rgb time_colour(double f) {
  // Viridis at five stops, linearly interpolated.
  static const Rgb stops[] = {{68, 1, 84}, {59, 82, 139}, {33, 145, 140}, {94, 201, 98}, {253, 231, 37}};
  f = std::clamp(std::isfinite(f) ? f : 0.0, 0.0, 1.0) * 4.0;
  const int i = std::min(3, static_cast<int>(f));
  const double t = f - i;
  const auto mix = [t](int a, int b) { return static_cast<int>(std::lround(a + (b - a) * t)); };
  return {mix(stops[i].r, stops[i + 1].r), mix(stops[i].g, stops[i + 1].g), mix(stops[i].b, stops[i + 1].b)};
}

FigurePanel& Figure::add_panel(std::string title) {
  panels_.emplace_back(std::move(title));
  return panels_.back();
}

namespace {

// ---- Layout (px) ----
constexpr double kTitleH = 52;   // figure title band
constexpr double kLeft = 66;     // panel: tick labels left of the data
constexpr double kRight = 22;
constexpr double kTop = 40;      // panel title
constexpr double kBottom = 56;   // tick labels and the x axis label
constexpr double kData = 660;    // square data area
constexpr double kPanelW = kLeft + kData + kRight;
constexpr double kPanelH = kTop + kData + kBottom;
constexpr double kLegendW = 400;
constexpr std::size_t kWrap = 44;  // legend characters per line

const Rgb kInk{30, 30, 30};
const Rgb kGridColour{228, 228, 228};
const Rgb kAxisColour{90, 90, 90};
const Rgb kNoteColour{90, 90, 90};

struct P {
  double x = 0.0;
  double y = 0.0;
};
enum class Anchor { Start, Middle, End };

struct Meta {
  std::string cls;
  std::string name;
};

class Painter {
 public:
  virtual ~Painter() = default;
  virtual void begin_group(const std::string& cls, const std::string& title) = 0;
  virtual void end_group() = 0;
  virtual void polyline(const std::vector<P>& pts, Rgb c, double width, const Meta& m) = 0;
  virtual void polygon(const std::vector<P>& pts, Rgb fill, const Meta& m) = 0;
  virtual void circle(P c, double r, Rgb colour, bool filled, double width, const Meta& m) = 0;
  virtual void text(P at, const std::string& s, Rgb c, double size, Anchor anchor, const Meta& m) = 0;
};

// ---- PNG ----
constexpr int kShift = 3;  // sub-pixel bits for OpenCV's anti-aliased drawing
cv::Point fixed(P p) { return {static_cast<int>(std::lround(p.x * (1 << kShift))), static_cast<int>(std::lround(p.y * (1 << kShift)))}; }
cv::Scalar bgr(Rgb c) { return {static_cast<double>(c.b), static_cast<double>(c.g), static_cast<double>(c.r)}; }
int thickness(double w) { return std::max(1, static_cast<int>(std::lround(w))); }

class RasterPainter : public Painter {
 public:
  RasterPainter(int w, int h) : image_(h, w, CV_8UC3, cv::Scalar(255, 255, 255)) {}
  void begin_group(const std::string&, const std::string&) override {}
  void end_group() override {}
  void polyline(const std::vector<P>& pts, Rgb c, double width, const Meta&) override {
    std::vector<cv::Point> v;
    v.reserve(pts.size());
    for (const P& p : pts) v.push_back(fixed(p));
    cv::polylines(image_, v, false, bgr(c), thickness(width), cv::LINE_AA, kShift);
  }
  void polygon(const std::vector<P>& pts, Rgb fill, const Meta&) override {
    std::vector<cv::Point> v;
    for (const P& p : pts) v.push_back(fixed(p));
    cv::fillPoly(image_, std::vector<std::vector<cv::Point>>{v}, bgr(fill), cv::LINE_AA, kShift);
  }
  void circle(P c, double r, Rgb colour, bool filled, double width, const Meta&) override {
    const int radius = std::max(1, static_cast<int>(std::lround(r * (1 << kShift))));
    cv::circle(image_, fixed(c), radius, bgr(colour), filled ? cv::FILLED : thickness(width), cv::LINE_AA, kShift);
  }
  void text(P at, const std::string& s, Rgb c, double size, Anchor anchor, const Meta&) override {
    const double scale = size / 30.0;
    const int thick = size >= 19 ? 2 : 1;
    int baseline = 0;
    const cv::Size ts = cv::getTextSize(s, cv::FONT_HERSHEY_SIMPLEX, scale, thick, &baseline);
    double x = at.x;
    if (anchor == Anchor::Middle) x -= ts.width / 2.0;
    if (anchor == Anchor::End) x -= ts.width;
    cv::putText(image_, s, {static_cast<int>(std::lround(x)), static_cast<int>(std::lround(at.y))},
                cv::FONT_HERSHEY_SIMPLEX, scale, bgr(c), thick, cv::LINE_AA);
  }
  void save(const std::string& path) const {
    figure::write_png(path, image_.data, image_.cols, image_.rows, image_.channels(), image_.step[0]);
  }

 private:
  cv::Mat image_;
};

// ---- SVG ----
std::string escape(const std::string& s) {
  std::string out;
  for (char ch : s) {
    switch (ch) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += ch;
    }
  }
  return out;
}

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f", v);
  return buf;
}

std::string colour(Rgb c) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "#%02x%02x%02x", c.r & 0xff, c.g & 0xff, c.b & 0xff);
  return buf;
}

class SvgPainter : public Painter {
 public:
  SvgPainter(double w, double h) {
    out_ << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
         << "<svg xmlns=\"http://www.w3.org/2000/svg\" version=\"1.1\" width=\"" << num(w) << "\" height=\"" << num(h)
         << "\" viewBox=\"0 0 " << num(w) << " " << num(h) << "\" font-family=\"DejaVu Sans, Helvetica, Arial, sans-serif\">\n"
         << "<rect width=\"100%\" height=\"100%\" fill=\"#ffffff\"/>\n";
  }
  void begin_group(const std::string& cls, const std::string& title) override {
    out_ << "<g class=\"" << escape(cls) << "\">";
    if (!title.empty()) out_ << "<title>" << escape(title) << "</title>";
    out_ << "\n";
  }
  void end_group() override { out_ << "</g>\n"; }
  void polyline(const std::vector<P>& pts, Rgb c, double width, const Meta& m) override {
    out_ << "<polyline" << attrs(m) << " points=\"" << points(pts) << "\" fill=\"none\" stroke=\"" << colour(c)
         << "\" stroke-width=\"" << num(width) << "\" stroke-linejoin=\"round\" stroke-linecap=\"round\"" << close(m, "polyline");
  }
  void polygon(const std::vector<P>& pts, Rgb fill, const Meta& m) override {
    out_ << "<polygon" << attrs(m) << " points=\"" << points(pts) << "\" fill=\"" << colour(fill) << "\"" << close(m, "polygon");
  }
  void circle(P c, double r, Rgb col, bool filled, double width, const Meta& m) override {
    out_ << "<circle" << attrs(m) << " cx=\"" << num(c.x) << "\" cy=\"" << num(c.y) << "\" r=\"" << num(r) << "\"";
    if (filled) {
      out_ << " fill=\"" << colour(col) << "\"";
    } else {
      out_ << " fill=\"none\" stroke=\"" << colour(col) << "\" stroke-width=\"" << num(width) << "\"";
    }
    out_ << close(m, "circle");
  }
  void text(P at, const std::string& s, Rgb c, double size, Anchor anchor, const Meta& m) override {
    const char* a = anchor == Anchor::Middle ? "middle" : anchor == Anchor::End ? "end" : "start";
    out_ << "<text" << attrs(m) << " x=\"" << num(at.x) << "\" y=\"" << num(at.y) << "\" font-size=\"" << num(size)
         << "\" fill=\"" << colour(c) << "\" text-anchor=\"" << a << "\">" << escape(s) << "</text>\n";
  }
  void save(const std::string& path) {
    out_ << "</svg>\n";
    std::ofstream f(path);
    f << out_.str();
    if (!f) throw std::runtime_error("cannot write " + path);
  }

 private:
  static std::string attrs(const Meta& m) {
    std::string s;
    if (!m.cls.empty()) s += " class=\"" + escape(m.cls) + "\"";
    if (!m.name.empty()) s += " data-name=\"" + escape(m.name) + "\"";
    return s;
  }
  // Ends an element; a named one carries its name as a <title> (a tooltip in a browser).
  static std::string close(const Meta& m, const char* tag) {
    return m.name.empty() ? "/>\n" : "><title>" + escape(m.name) + "</title></" + std::string(tag) + ">\n";
  }
  static std::string points(const std::vector<P>& pts) {
    std::string s;
    for (const P& p : pts) s += num(p.x) + "," + num(p.y) + " ";
    if (!s.empty()) s.pop_back();
    return s;
  }
  std::ostringstream out_;
};

// ---- Shared layout and painting ----

double nice_step(double span) {
  const double raw = span / 6.0;
  const double base = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0}) {
    if (base * m >= raw) return base * m;
  }
  return base * 10.0;
}

std::string tick_label(double v, double step) {
  v = std::round(v / step) * step;
  if (std::abs(v) < step * 1e-6) v = 0.0;
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

std::vector<std::string> wrap(const std::string& text, std::size_t width) {
  std::vector<std::string> lines;
  std::istringstream words(text);
  std::string line;
  for (std::string w; words >> w;) {
    if (!line.empty() && line.size() + 1 + w.size() > width) {
      lines.push_back(line);
      line.clear();
    }
    line += (line.empty() ? "" : " ") + w;
  }
  if (!line.empty()) lines.push_back(line);
  return lines;
}

struct Axes {
  double cx = 0.0, cy = 0.0, span = 1.0;  // world window: centre and side (m)
};

Axes axes_for(double x0, double x1, double y0, double y1) {
  Axes a;
  a.cx = 0.5 * x0 + 0.5 * x1;  // halves first: the sum of two huge values overflows
  a.cy = 0.5 * y0 + 0.5 * y1;
  a.span = std::max({x1 - x0, y1 - y0, 0.5}) * 1.08;
  return a;
}

// How far from the origin, in spans, a window may lie: beyond, a pixel (span / 660) is finer than the
// doubles there resolve (a relative 2.2e-16), and grid steps vanish in the rounding of the values.
constexpr double kMaxReachInSpans = 1e9;

// Throws, naming the figure and panel, when a window cannot be drawn: not finite, or so far from
// the origin for its size that its coordinates no longer resolve it.
void check_drawable(const Axes& a, const std::string& figure, const std::string& panel) {
  const double reach = std::max(std::abs(a.cx), std::abs(a.cy)) + a.span / 2.0;
  char what[160];
  if (!std::isfinite(reach)) {
    std::snprintf(what, sizeof what, "the data's extent is not finite");
  } else if (reach > a.span * kMaxReachInSpans) {
    std::snprintf(what, sizeof what, "its data lie %.3g m from the origin, more than %.0e times the window's %.3g m: "
                  "too far out to draw at that scale", reach, kMaxReachInSpans, a.span);
  } else {
    return;
  }
  throw std::runtime_error("cannot plot '" + figure + "', panel '" + panel + "': " + what);
}

// The multiples of `step` within [lo, hi] (and a hair beyond hi), counted with an integer: the loop
// ends whatever the rounding of the values. At most 64; a drawable window has about 6.
std::vector<double> grid_values(double lo, double hi, double step) {
  const double first = std::ceil(lo / step);
  const double last = std::floor(hi / step + 1e-9);
  std::vector<double> v;
  for (int k = 0; k < 64 && first + k <= last; ++k) v.push_back((first + k) * step);
  return v;
}

// The figure's width, height and legend height for `panels` panels.
double legend_height(const std::vector<LegendEntry>& legend, bool bar) {
  double h = 16;
  for (const LegendEntry& e : legend) h += 24.0 * static_cast<double>(std::max<std::size_t>(1, wrap(e.text, kWrap).size()));
  if (bar) h += 90;
  return h;
}

}  // namespace

namespace {

void paint(const std::string& title, const std::vector<FigurePanel>& panels, const std::vector<LegendEntry>& legend,
           const ColourBar* bar, bool share_axes, Painter& out, double width) {
  const Meta none;
  out.text({width / 2.0, 34}, title, kInk, 21, Anchor::Middle, {"figure-title", ""});

  std::vector<Axes> axes;
  double ux0 = std::numeric_limits<double>::infinity(), ux1 = -ux0, uy0 = ux0, uy1 = -ux0;
  for (const FigurePanel& p : panels) {
    double x0, x1, y0, y1;
    if (!p.extent(x0, x1, y0, y1)) x0 = y0 = -1, x1 = y1 = 1;
    axes.push_back(axes_for(x0, x1, y0, y1));
    ux0 = std::min(ux0, x0), ux1 = std::max(ux1, x1), uy0 = std::min(uy0, y0), uy1 = std::max(uy1, y1);
  }
  if (share_axes) {
    for (Axes& a : axes) a = axes_for(ux0, ux1, uy0, uy1);
  }
  for (std::size_t i = 0; i < panels.size(); ++i) check_drawable(axes[i], title, panels[i].title());

  for (std::size_t i = 0; i < panels.size(); ++i) {
    const FigurePanel& panel = panels[i];
    const Axes& a = axes[i];
    const double left = static_cast<double>(i) * kPanelW + kLeft;
    const double top = kTitleH + kTop;
    const double scale = kData / a.span;
    const auto px = [&](Xy w) {
      return P{left + kData / 2.0 + (w.x - a.cx) * scale, top + kData / 2.0 - (w.y - a.cy) * scale};
    };
    out.begin_group("panel", panel.title());
    out.text({left + kData / 2.0, top - 14}, panel.title(), kInk, 17, Anchor::Middle, {"panel-title", ""});

    // Grid, box, ticks.
    out.begin_group("axes", "");
    const double step = nice_step(a.span);
    const double xlo = a.cx - a.span / 2.0, xhi = a.cx + a.span / 2.0;
    const double ylo = a.cy - a.span / 2.0, yhi = a.cy + a.span / 2.0;
    for (const double v : grid_values(xlo, xhi, step)) {
      const double x = px({v, 0}).x;
      out.polyline({{x, top}, {x, top + kData}}, kGridColour, 1, {"grid", ""});
      out.polyline({{x, top + kData}, {x, top + kData + 6}}, kAxisColour, 1, none);
      out.text({x, top + kData + 22}, tick_label(v, step), kInk, 13, Anchor::Middle, {"tick-label", ""});
    }
    for (const double v : grid_values(ylo, yhi, step)) {
      const double y = px({0, v}).y;
      out.polyline({{left, y}, {left + kData, y}}, kGridColour, 1, {"grid", ""});
      out.polyline({{left - 6, y}, {left, y}}, kAxisColour, 1, none);
      out.text({left - 9, y + 5}, tick_label(v, step), kInk, 13, Anchor::End, {"tick-label", ""});
    }
    out.polyline({{left, top}, {left + kData, top}, {left + kData, top + kData}, {left, top + kData}, {left, top}},
                 kAxisColour, 1, {"frame", ""});
    out.text({left + kData / 2.0, top + kData + 46}, "x (m), " + panel.frame(), kInk, 14, Anchor::Middle, {"axis-label", ""});
    out.text({left - 60, top - 8}, "y (m)", kInk, 14, Anchor::Start, {"axis-label", ""});
    out.end_group();

    for (const FigureItem& it : panel.items()) {
      const Meta m{it.cls, it.name};
      switch (it.kind) {
        case FigureItem::Kind::Polyline: {
          std::vector<P> pts;
          pts.reserve(it.points.size());
          for (const Xy& w : it.points) pts.push_back(px(w));
          out.polyline(pts, it.colour, it.size, m);
          break;
        }
        case FigureItem::Kind::Polygon: {
          std::vector<P> pts;
          for (const Xy& w : it.points) pts.push_back(px(w));
          out.polygon(pts, it.colour, m);
          break;
        }
        case FigureItem::Kind::Disc:
          out.circle(px(it.points[0]), std::max(1.5, it.size * scale), it.colour, true, 0, m);
          break;
        case FigureItem::Kind::Marker:
          out.circle(px(it.points[0]), it.size, it.colour, it.filled, 1.5, m);
          break;
        case FigureItem::Kind::Tick: {
          const P p = px(it.points[0]);
          out.polyline({p, {p.x + it.size * std::cos(it.angle), p.y - it.size * std::sin(it.angle)}}, it.colour, 1.2, m);
          break;
        }
        case FigureItem::Kind::Text:
          out.text(px(it.points[0]), it.text, it.colour, it.size,
                   it.anchor < 0 ? Anchor::Start : it.anchor > 0 ? Anchor::End : Anchor::Middle, m);
          break;
      }
    }
    out.end_group();
  }

  // Legend.
  out.begin_group("legend", "");
  const double lx = static_cast<double>(panels.size()) * kPanelW + 14;
  double ly = kTitleH + kTop + 12;
  out.polyline({{lx - 6, kTitleH + kTop}, {lx - 6, kTitleH + kTop + kData}}, kGridColour, 1, none);
  for (const LegendEntry& e : legend) {
    const std::vector<std::string> lines = wrap(e.text, kWrap);
    const P at{lx + 14, ly};
    switch (e.kind) {
      case LegendEntry::Kind::Line: out.polyline({{at.x - 11, at.y}, {at.x + 11, at.y}}, e.colour, e.size, none); break;
      case LegendEntry::Kind::Dot: out.circle(at, e.size, e.colour, true, 0, none); break;
      case LegendEntry::Kind::Ring: out.circle(at, e.size, e.colour, false, 1.5, none); break;
      case LegendEntry::Kind::Tick:
        out.circle(at, e.size, e.colour, false, 1.5, none);
        out.polyline({at, {at.x + 11, at.y}}, e.colour, 1.2, none);
        break;
      case LegendEntry::Kind::Note: break;
    }
    const bool note = e.kind == LegendEntry::Kind::Note;
    for (std::size_t k = 0; k < lines.size(); ++k) {
      out.text({note ? lx : lx + 36, ly + 5 + 19.0 * static_cast<double>(k)}, lines[k], note ? kNoteColour : kInk, 14,
               Anchor::Start, {"legend-text", ""});
    }
    ly += 24.0 * static_cast<double>(std::max<std::size_t>(1, lines.size()));
  }
  if (bar != nullptr) {
    ly += 10;
    out.text({lx, ly}, bar->label, kInk, 14, Anchor::Start, {"legend-text", ""});
    ly += 10;
    constexpr int kSteps = 64;
    constexpr double kBarW = 300;
    for (int k = 0; k < kSteps; ++k) {
      const double x = lx + kBarW * k / kSteps;
      const double w = kBarW / kSteps + 0.6;  // overlap: no hairline gaps
      out.polygon({{x, ly}, {x + w, ly}, {x + w, ly + 16}, {x, ly + 16}}, time_colour((k + 0.5) / kSteps), {"colour-bar", ""});
    }
    for (int k = 0; k <= 4; ++k) {
      const double x = lx + kBarW * k / 4.0;
      const double v = bar->min + (bar->max - bar->min) * k / 4.0;
      char buf[32];
      std::snprintf(buf, sizeof buf, "%.0f", v);
      out.polyline({{x, ly + 16}, {x, ly + 21}}, kAxisColour, 1, none);
      out.text({x, ly + 36}, buf, kInk, 13, Anchor::Middle, {"tick-label", ""});
    }
  }
  out.end_group();
}

}  // namespace

void Figure::write_png(const std::string& path) const {
  const double w = static_cast<double>(panels_.size()) * kPanelW + kLegendW;
  const double h = std::max(kTitleH + kPanelH, kTitleH + kTop + legend_height(legend_, has_bar_) + 20);
  RasterPainter p(static_cast<int>(w), static_cast<int>(h));
  paint(title_, panels_, legend_, has_bar_ ? &bar_ : nullptr, share_axes_, p, w);
  p.save(path);
}

void Figure::write_svg(const std::string& path) const {
  const double w = static_cast<double>(panels_.size()) * kPanelW + kLegendW;
  const double h = std::max(kTitleH + kPanelH, kTitleH + kTop + legend_height(legend_, has_bar_) + 20);
  SvgPainter p(w, h);
  paint(title_, panels_, legend_, has_bar_ ? &bar_ : nullptr, share_axes_, p, w);
  p.save(path);
}

}  // namespace whiskeye::figure

// Pictures of a world (see world_plots.h).
#include "whiskeye/sim/world_plots.h"

#include "whiskeye/figure/png_file.h"
#include "whiskeye/sim/renderer.h"

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <iterator>

namespace whiskeye::sim {

namespace {

using figure::Figure;
using figure::FigurePanel;
using figure::LegendEntry;
using figure::Rgb;
using figure::Xy;

const Rgb kWall{105, 105, 105};
const Rgb kSolid{80, 80, 80};
// Visual landmarks by pattern: landmarks that look alike get one colour.
const Rgb kPatternColours[] = {{140, 70, 170}, {0, 128, 128}, {150, 95, 40}, {200, 80, 150}, {110, 110, 20}};
const Rgb kTrajectory{200, 0, 200};
const Rgb kHeadPath{230, 160, 230};
const Rgb kStart{255, 0, 0};

// A label `by` metres from `p` along `dir` (a unit vector), anchored so that the text runs away
// from p: right of it, left of it, or centred above or below it.
void label(FigurePanel& panel, Xy p, Xy dir, double by, const std::string& text, Rgb colour) {
  const bool sideways = std::abs(dir.x) > std::abs(dir.y);
  const int anchor = sideways ? (dir.x > 0 ? -1 : 1) : 0;
  // Text hangs from its baseline: below a point it needs its height more.
  const double drop = !sideways && dir.y < 0 ? 0.1 : 0.0;
  panel.text({p.x + by * dir.x, p.y + by * dir.y - drop}, text, colour, 13, "landmark-label", anchor);
}

// A circle as a closed polyline of 1° steps.
std::vector<Xy> circle(Point2 centre, double radius) {
  std::vector<Xy> pts;
  for (int k = 0; k <= 360; ++k) {
    const double a = deg_to_rad(static_cast<double>(k));
    pts.push_back({centre.x + radius * std::cos(a), centre.y + radius * std::sin(a)});
  }
  return pts;
}

// "3.14": the first four characters of the number, as the title has always shown them.
std::string short_number(double v) { return std::to_string(v).substr(0, 4); }

}  // namespace

void draw_world(FigurePanel& panel, const World& world) {
  const Xy centre{world.trajectory.centre.x, world.trajectory.centre.y};
  const auto towards_centre = [&](Xy p) {
    const double dx = centre.x - p.x, dy = centre.y - p.y;
    const double n = std::max(1e-9, std::hypot(dx, dy));
    return Xy{dx / n, dy / n};
  };
  for (const Panel& w : world.walls) {
    panel.polyline({{w.from.x, w.from.y}, {w.to.x, w.to.y}}, kWall, 5, "wall", w.name);
  }
  for (const Panel& l : world.landmarks) {
    const std::size_t k = static_cast<std::size_t>(std::max(0, l.pattern)) % std::size(kPatternColours);
    const std::string pattern = l.pattern >= 0 && static_cast<std::size_t>(l.pattern) < world.patterns.size()
                                    ? world.patterns[static_cast<std::size_t>(l.pattern)].name
                                    : "";
    const std::string name = pattern.empty() ? l.name : l.name + " (" + pattern + ")";
    panel.polyline({{l.from.x, l.from.y}, {l.to.x, l.to.y}}, kPatternColours[k], 10, "visual-landmark", name);
    const Xy mid{0.5 * (l.from.x + l.to.x), 0.5 * (l.from.y + l.to.y)};
    label(panel, mid, towards_centre(mid), 0.2, name, kPatternColours[k]);
  }
  for (const Solid& s : world.solids) {
    if (s.shape == Solid::Shape::Circle) {
      panel.disc({s.centre.x, s.centre.y}, s.radius, kSolid, "tactile-landmark", s.name);
    } else {
      std::vector<Xy> pts;
      for (const Point2& q : s.vertices) pts.push_back({q.x, q.y});
      panel.polygon(pts, kSolid, "tactile-landmark", s.name);
    }
    // Above an object beyond the centre's north, else below it: clear of the map and of the wall
    // landmarks' labels, which run along the walls.
    const Xy in = towards_centre({s.centre.x, s.centre.y});
    label(panel, {s.centre.x, s.centre.y}, {0.0, -in.y > 0.5 ? 1.0 : -1.0}, s.radius + 0.1, s.name, kSolid);
  }
}

void world_legend(Figure& fig) {
  fig.legend({LegendEntry::Kind::Line, kWall, 5, "wall"});
  fig.legend({LegendEntry::Kind::Line, kPatternColours[1], 8, "visual landmark (one colour per pattern)"});
  fig.legend({LegendEntry::Kind::Dot, kSolid, 6, "tactile landmark"});
}

void plot_world(const World& world, const RobotGeometry& robot, const std::string& path) {
  const Trajectory& t = world.trajectory;
  const std::string title = world.name + ": " + std::to_string(t.laps) + " laps, r = " + short_number(t.radius) +
                            " m, " + short_number(t.speed) + " m/s " + (t.counter_clockwise ? "ccw" : "cw") +
                            ", facing " + (t.outwards ? "outwards" : "inwards");
  Figure fig(title);
  FigurePanel& panel = fig.add_panel("top-down");
  panel.set_frame("world frame");
  draw_world(panel, world);
  panel.polyline(circle(t.centre, t.radius), kTrajectory, 2, "trajectory");
  panel.polyline(circle(t.centre, head_path_radius(t.radius, robot)), kHeadPath, 1, "head-path");
  // The start: the base's position, and its heading as a 0.4 m arrow.
  const Pose2 start = t.pose_at(0.0);
  const Xy tip{start.x + 0.4 * std::cos(start.theta), start.y + 0.4 * std::sin(start.theta)};
  const auto barb = [&](double side) {
    const double a = start.theta + side * deg_to_rad(150.0);
    return Xy{tip.x + 0.12 * std::cos(a), tip.y + 0.12 * std::sin(a)};
  };
  panel.polyline({{start.x, start.y}, tip}, kStart, 2, "start-heading");
  panel.polyline({barb(1.0), tip, barb(-1.0)}, kStart, 2, "start-heading");
  panel.marker({start.x, start.y}, 6, kStart, true, "start");
  world_legend(fig);
  fig.legend({LegendEntry::Kind::Line, kTrajectory, 2, "trajectory (the base's path)"});
  fig.legend({LegendEntry::Kind::Line, kHeadPath, 1, "the head's path"});
  fig.legend({LegendEntry::Kind::Dot, kStart, 6, "start: the base's position, its heading"});
  fig.write_png(path);
}

void plot_views(const World& world, const RobotGeometry& robot, const std::vector<double>& angles_deg,
                const std::string& path) {
  World w = world;
  w.camera.sigma = 0.0;
  Renderer renderer(w, robot);
  FastRng rng(1);
  const int tw = renderer.width() / 2;
  const int th = renderer.height() / 2;
  const int cols = std::min<int>(2, static_cast<int>(angles_deg.size()));
  const int rows = (static_cast<int>(angles_deg.size()) + 1) / 2;
  cv::Mat out(rows * th, cols * tw, CV_8UC1, cv::Scalar(255));
  for (std::size_t i = 0; i < angles_deg.size(); ++i) {
    Trajectory t = w.trajectory;
    t.start_angle = deg_to_rad(angles_deg[i]);
    std::vector<uint8_t> grey;
    renderer.render(t.pose_at(0.0), 0.0, rng, grey);
    const cv::Mat full(renderer.height(), renderer.width(), CV_8UC1, grey.data());
    cv::Mat tile = out(cv::Rect(static_cast<int>(i % 2) * tw, static_cast<int>(i / 2) * th, tw, th));
    cv::resize(full, tile, tile.size(), 0, 0, cv::INTER_AREA);
    const std::string label = "polar angle " + std::to_string(static_cast<int>(std::lround(angles_deg[i]))) + " deg";
    cv::rectangle(tile, cv::Rect(0, 0, 190, 22), cv::Scalar(255), cv::FILLED);
    cv::putText(tile, label, cv::Point(5, 16), cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(0), 1, cv::LINE_AA);
  }
  figure::write_png(path, out.data, out.cols, out.rows, out.channels(), out.step[0]);
}

}  // namespace whiskeye::sim

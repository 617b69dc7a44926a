// vita-sim's pictures of a world (see world_plots.h).
#include "whiskeye/sim/world_plots.h"

#include "png_file.h"
#include "whiskeye/sim/renderer.h"

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <limits>

namespace whiskeye::sim {

void plot_world(const World& world, const RobotGeometry& robot, const std::string& path) {
  double x0 = std::numeric_limits<double>::infinity();
  double y0 = x0;
  double x1 = -x0;
  double y1 = -x0;
  for (const Panel& p : world.walls) {
    for (const Point2& q : {p.from, p.to}) {
      x0 = std::min(x0, q.x);
      y0 = std::min(y0, q.y);
      x1 = std::max(x1, q.x);
      y1 = std::max(y1, q.y);
    }
  }
  if (!std::isfinite(x0)) {
    const Trajectory& t = world.trajectory;
    x0 = t.centre.x - t.radius - 1.0;
    x1 = t.centre.x + t.radius + 1.0;
    y0 = t.centre.y - t.radius - 1.0;
    y1 = t.centre.y + t.radius + 1.0;
  }
  const double scale = 100.0;
  const int margin = 60;
  const int W = static_cast<int>((x1 - x0) * scale) + 2 * margin;
  const int H = static_cast<int>((y1 - y0) * scale) + 2 * margin;
  cv::Mat img(H, W, CV_8UC3, cv::Scalar(255, 255, 255));
  auto px = [&](double x, double y) {
    return cv::Point(static_cast<int>(std::lround(margin + (x - x0) * scale)),
                     static_cast<int>(std::lround(H - margin - (y - y0) * scale)));
  };
  const cv::Scalar black(0, 0, 0);
  const cv::Scalar colours[] = {{200, 60, 20}, {20, 140, 20}, {20, 20, 200}, {160, 20, 160}, {0, 140, 200}};
  for (const Panel& p : world.walls) cv::line(img, px(p.from.x, p.from.y), px(p.to.x, p.to.y), cv::Scalar(120, 120, 120), 6);
  for (const Panel& p : world.landmarks) {
    const cv::Scalar c = colours[static_cast<std::size_t>(p.pattern) % 5];
    cv::line(img, px(p.from.x, p.from.y), px(p.to.x, p.to.y), c, 12);
    const Point2 mid{0.5 * (p.from.x + p.to.x), 0.5 * (p.from.y + p.to.y)};
    const double dx = world.trajectory.centre.x - mid.x;
    const double dy = world.trajectory.centre.y - mid.y;
    const double n = std::hypot(dx, dy);
    const std::string label = p.name + " (" + world.patterns[static_cast<std::size_t>(p.pattern)].name + ")";
    int baseline = 0;
    const cv::Size size = cv::getTextSize(label, cv::FONT_HERSHEY_SIMPLEX, 0.45, 1, &baseline);
    // Centred, far enough inwards that the text clears the wall.
    const double inset = 0.3 + 0.5 * size.width / scale * std::abs(dx / n);
    const cv::Point at = px(mid.x + inset * dx / n, mid.y + inset * dy / n);
    cv::putText(img, label, at - cv::Point(size.width / 2, -size.height / 2), cv::FONT_HERSHEY_SIMPLEX, 0.45, c, 1,
                cv::LINE_AA);
  }
  const Trajectory& t = world.trajectory;
  cv::circle(img, px(t.centre.x, t.centre.y), static_cast<int>(t.radius * scale), cv::Scalar(200, 0, 200), 2, cv::LINE_AA);
  const double head_r = head_path_radius(t.radius, robot);  // the head's path
  cv::circle(img, px(t.centre.x, t.centre.y), static_cast<int>(head_r * scale), cv::Scalar(230, 160, 230), 1, cv::LINE_AA);
  for (const Solid& s : world.solids) {
    const cv::Scalar c(40, 40, 40);
    if (s.shape == Solid::Shape::Circle) {
      cv::circle(img, px(s.centre.x, s.centre.y), std::max(2, static_cast<int>(s.radius * scale)), c, cv::FILLED, cv::LINE_AA);
    } else {
      std::vector<cv::Point> poly;
      for (const Point2& q : s.vertices) poly.push_back(px(q.x, q.y));
      cv::fillPoly(img, std::vector<std::vector<cv::Point>>{poly}, c, cv::LINE_AA);
    }
    // Labels inside the path, clear of the wall landmarks' labels.
    const double dx = s.centre.x - t.centre.x;
    const double dy = s.centre.y - t.centre.y;
    const double n = std::max(1e-9, std::hypot(dx, dy));
    const cv::Point at = px(s.centre.x - 0.75 * dx / n, s.centre.y - 0.75 * dy / n);
    cv::putText(img, s.name, at - cv::Point(static_cast<int>(s.name.size()) * 4, -4), cv::FONT_HERSHEY_SIMPLEX, 0.45,
                black, 1, cv::LINE_AA);
  }
  // Start pose: base position and heading.
  const Pose2 start = t.pose_at(0.0);
  const cv::Point a = px(start.x, start.y);
  const cv::Point b = px(start.x + 0.4 * std::cos(start.theta), start.y + 0.4 * std::sin(start.theta));
  cv::arrowedLine(img, a, b, cv::Scalar(0, 0, 255), 2, cv::LINE_AA, 0, 0.3);
  cv::circle(img, a, 6, cv::Scalar(0, 0, 255), cv::FILLED, cv::LINE_AA);
  double vx;
  double vy;
  double om;
  t.body_velocity(vx, vy, om);
  const std::string title = world.name + ": " + std::to_string(t.laps) + " laps, r = " +
                            std::to_string(t.radius).substr(0, 4) + " m, " + std::to_string(t.speed).substr(0, 4) +
                            " m/s " + (t.counter_clockwise ? "ccw" : "cw") + ", facing " +
                            (t.outwards ? "outwards" : "inwards") + "; red: start";
  cv::putText(img, title, cv::Point(10, 25), cv::FONT_HERSHEY_SIMPLEX, 0.5, black, 1, cv::LINE_AA);
  write_png(path, img.data, img.cols, img.rows, img.channels(), img.step[0]);
}

// Noise-free camera views at the given polar angles of the trajectory, tiled two per row at half
// size with their angle written on them: to check a world's visual aliasing by eye.
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
  write_png(path, out.data, out.cols, out.rows, out.channels(), out.step[0]);
}

}  // namespace whiskeye::sim

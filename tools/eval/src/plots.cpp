// Draws with OpenCV (imgproc + imgcodecs only): world coordinates mapped to pixels with equal scale
// on both axes, y up, a metric scale bar and a legend on every plot.
#include "plots.h"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

namespace whiskeye::eval {

namespace {

constexpr int kSize = 900;          // px, square canvas
constexpr int kTop = 60;            // px reserved for the title
constexpr int kMargin = 40;         // px around the data
constexpr int kLegendWidth = 420;   // px, panel right of the data so the legend never hides it

const cv::Scalar kWhite(255, 255, 255);
const cv::Scalar kBlack(0, 0, 0);
const cv::Scalar kGrey(170, 170, 170);
const cv::Scalar kBlue(200, 110, 30);
const cv::Scalar kOrange(0, 140, 255);
const cv::Scalar kGreen(40, 160, 40);
const cv::Scalar kRed(40, 40, 220);

class Canvas {
 public:
  Canvas(double min_x, double max_x, double min_y, double max_y) : image_(kSize, kSize + kLegendWidth, CV_8UC3, kWhite) {
    const double span = std::max({max_x - min_x, max_y - min_y, 0.5});
    const int usable = kSize - kTop - 2 * kMargin;
    scale_ = usable / span;
    cx_ = 0.5 * (min_x + max_x);
    cy_ = 0.5 * (min_y + max_y);
  }

  cv::Point px(double x, double y) const {
    const double centre_col = kSize / 2.0;
    const double centre_row = kTop + (kSize - kTop) / 2.0;
    return {static_cast<int>(std::lround(centre_col + (x - cx_) * scale_)),
            static_cast<int>(std::lround(centre_row - (y - cy_) * scale_))};
  }

  cv::Mat& image() { return image_; }

  void title(const std::string& text) {
    cv::putText(image_, text, {20, 38}, cv::FONT_HERSHEY_SIMPLEX, 0.75, kBlack, 2, cv::LINE_AA);
  }

  // A bar of a round length about a fifth of the canvas, bottom right.
  void scale_bar() {
    const double target_m = (kSize / 5.0) / scale_;
    double length = 0.01;
    for (double base = 0.01; base < 1e4; base *= 10) {
      for (double m : {1.0, 2.0, 5.0}) {
        if (base * m <= target_m) length = base * m;
      }
    }
    const int len_px = static_cast<int>(std::lround(length * scale_));
    const cv::Point right(kSize - 40, kSize - 30);
    const cv::Point left(right.x - len_px, right.y);
    cv::line(image_, left, right, kBlack, 3);
    cv::line(image_, left + cv::Point(0, -6), left + cv::Point(0, 6), kBlack, 2);
    cv::line(image_, right + cv::Point(0, -6), right + cv::Point(0, 6), kBlack, 2);
    char label[32];
    std::snprintf(label, sizeof label, "%g m", length);
    cv::putText(image_, label, {left.x, left.y - 12}, cv::FONT_HERSHEY_SIMPLEX, 0.6, kBlack, 1, cv::LINE_AA);
  }

  // Legend entries drawn by `marker(image, centre)`, in the panel right of the data.
  template <typename Marker>
  void legend_entry(int index, const std::string& text, Marker marker) {
    if (index == 0) cv::line(image_, {kSize, kTop}, {kSize, kSize - 20}, kGrey, 1);
    const cv::Point at(kSize + 25, kTop + 30 + 28 * index);
    marker(image_, at);
    cv::putText(image_, text, {at.x + 28, at.y + 6}, cv::FONT_HERSHEY_SIMPLEX, 0.55, kBlack, 1, cv::LINE_AA);
  }

  void save(const std::string& path) {
    bool ok = false;
    try {
      ok = cv::imwrite(path, image_);
    } catch (const cv::Exception& e) {
      throw std::runtime_error("cannot write " + path + ": " + e.what());
    }
    if (!ok) throw std::runtime_error("cannot write " + path);
  }

 private:
  cv::Mat image_;
  double scale_ = 1.0;  // px per m
  double cx_ = 0.0;
  double cy_ = 0.0;
};

struct Bounds {
  double min_x = std::numeric_limits<double>::infinity();
  double max_x = -std::numeric_limits<double>::infinity();
  double min_y = std::numeric_limits<double>::infinity();
  double max_y = -std::numeric_limits<double>::infinity();
  void add(double x, double y) {
    min_x = std::min(min_x, x);
    max_x = std::max(max_x, x);
    min_y = std::min(min_y, y);
    max_y = std::max(max_y, y);
  }
  Canvas canvas() const {
    if (!std::isfinite(min_x)) return Canvas(-1, 1, -1, 1);
    return Canvas(min_x, max_x, min_y, max_y);
  }
};

void draw_ground_truth(Canvas& c, const std::vector<PoseSample>& gt) {
  std::vector<cv::Point> pts;
  pts.reserve(gt.size());
  for (const PoseSample& s : gt) pts.push_back(c.px(s.pose.x, s.pose.y));
  if (pts.size() >= 2) cv::polylines(c.image(), pts, false, kGrey, 2, cv::LINE_AA);
}

std::vector<PoseSample> sorted_ground_truth(const EvalInput& input) {
  return GroundTruth(input.ground_truth).samples();
}

}  // namespace

void plot_experience_map(const std::string& path, const std::string& title, const EvalInput& input,
                         const EvalResult& result) {
  const std::vector<PoseSample> gt = sorted_ground_truth(input);
  const Pose2 T = result.alignment.valid ? result.alignment.T_world_map : Pose2{};
  Bounds b;
  for (const PoseSample& s : gt) b.add(s.pose.x, s.pose.y);
  std::vector<std::pair<Pose2, bool>> nodes;  // world pose, dense
  for (const MapExperience& e : input.map.experiences) {
    const Pose2 w = compose(T, e.pose);
    nodes.emplace_back(w, e.dense);
    b.add(w.x, w.y);
  }
  Canvas c = b.canvas();
  c.title(title + (result.alignment.valid ? "" : " (NOT ALIGNED: " + result.alignment.reason + ")"));
  draw_ground_truth(c, gt);
  for (const MapLink& l : input.map.links) {
    const MapExperience* i = input.map.find(l.from_id);
    const MapExperience* j = input.map.find(l.to_id);
    if (i == nullptr || j == nullptr) continue;
    const Pose2 wi = compose(T, i->pose);
    const Pose2 wj = compose(T, j->pose);
    cv::line(c.image(), c.px(wi.x, wi.y), c.px(wj.x, wj.y), kBlue, 1, cv::LINE_AA);
  }
  for (const auto& [w, dense] : nodes) {
    const cv::Point p = c.px(w.x, w.y);
    // A short tick shows the heading.
    const cv::Point h = p + cv::Point(static_cast<int>(std::lround(9 * std::cos(w.theta))),
                                      static_cast<int>(std::lround(-9 * std::sin(w.theta))));
    if (dense) {
      cv::circle(c.image(), p, 5, kOrange, cv::FILLED, cv::LINE_AA);
      cv::line(c.image(), p, h, kOrange, 1, cv::LINE_AA);
    } else {
      cv::circle(c.image(), p, 4, kBlue, 1, cv::LINE_AA);
      cv::line(c.image(), p, h, kBlue, 1, cv::LINE_AA);
    }
  }
  c.legend_entry(0, "ground truth", [](cv::Mat& im, cv::Point p) {
    cv::line(im, p - cv::Point(10, 0), p + cv::Point(10, 0), kGrey, 2, cv::LINE_AA);
  });
  c.legend_entry(1, "link", [](cv::Mat& im, cv::Point p) {
    cv::line(im, p - cv::Point(10, 0), p + cv::Point(10, 0), kBlue, 1, cv::LINE_AA);
  });
  c.legend_entry(2, "dense experience (contacts)", [](cv::Mat& im, cv::Point p) {
    cv::circle(im, p, 5, kOrange, cv::FILLED, cv::LINE_AA);
  });
  c.legend_entry(3, "sparse experience", [](cv::Mat& im, cv::Point p) {
    cv::circle(im, p, 4, kBlue, 1, cv::LINE_AA);
  });
  c.legend_entry(4, "tick: the experience's heading", [](cv::Mat& im, cv::Point p) {
    cv::circle(im, p, 4, kBlue, 1, cv::LINE_AA);
    cv::line(im, p, p + cv::Point(9, 0), kBlue, 1, cv::LINE_AA);
  });
  c.scale_bar();
  c.save(path);
}

void plot_relocalisations(const std::string& path, const std::string& title, const EvalInput& input,
                          const EvalResult& result, const EvalParams& params) {
  const std::vector<PoseSample> gt = sorted_ground_truth(input);
  Bounds b;
  for (const PoseSample& s : gt) b.add(s.pose.x, s.pose.y);
  Canvas c = b.canvas();
  c.title(title);
  draw_ground_truth(c, gt);
  std::size_t correct = 0;
  std::size_t incorrect = 0;
  // Incorrect ones last so they stay visible over correct ones.
  for (bool pass_correct : {true, false}) {
    for (const Relocalisation& r : result.exm.relocalisations) {
      if (r.correct != pass_correct) continue;
      const cv::Scalar colour = r.correct ? kGreen : kRed;
      const cv::Point now = c.px(r.gt_now.x, r.gt_now.y);
      const cv::Point target = c.px(r.gt_target_created.x, r.gt_target_created.y);
      cv::line(c.image(), now, target, colour, 2, cv::LINE_AA);
      cv::circle(c.image(), now, 4, colour, cv::FILLED, cv::LINE_AA);
      cv::circle(c.image(), target, 4, colour, 1, cv::LINE_AA);
      (r.correct ? correct : incorrect) += 1;
    }
  }
  char threshold[96];
  std::snprintf(threshold, sizeof threshold, "(correct: within %.3g m and %.3g deg)", params.correct_position_m,
                rad_to_deg(params.correct_angle_rad));
  c.legend_entry(0, "ground truth", [](cv::Mat& im, cv::Point p) {
    cv::line(im, p - cv::Point(10, 0), p + cv::Point(10, 0), kGrey, 2, cv::LINE_AA);
  });
  c.legend_entry(1, "correct re-localisation (" + std::to_string(correct) + ")", [](cv::Mat& im, cv::Point p) {
    cv::line(im, p - cv::Point(10, 0), p + cv::Point(10, 0), kGreen, 2, cv::LINE_AA);
  });
  c.legend_entry(2, "incorrect re-localisation (" + std::to_string(incorrect) + ")",
                 [](cv::Mat& im, cv::Point p) {
                   cv::line(im, p - cv::Point(10, 0), p + cv::Point(10, 0), kRed, 2, cv::LINE_AA);
                 });
  c.legend_entry(3, "dot: robot at the event", [](cv::Mat& im, cv::Point p) {
    cv::circle(im, p, 4, kBlack, cv::FILLED, cv::LINE_AA);
  });
  c.legend_entry(4, "ring: where the target was created", [](cv::Mat& im, cv::Point p) {
    cv::circle(im, p, 4, kBlack, 1, cv::LINE_AA);
  });
  c.legend_entry(5, threshold, [](cv::Mat&, cv::Point) {});
  c.scale_bar();
  c.save(path);
}

}  // namespace whiskeye::eval

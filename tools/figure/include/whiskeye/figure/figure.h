// A small vector figure for vita-eval's plots and vita-sim's map of a world: one or more panels side
// by side, each a list of drawing items in world coordinates (metres) with equal scale on both axes,
// metre axes with ticks and a grid, one legend and an optional colour bar; written as PNG (OpenCV
// raster, zlib file: png_file.h) and as SVG from the same items, so the two always show the same thing.
//
// The SVG writer is our own (figure.cpp, ~100 lines): no vector-graphics library (Cairo, an SVG
// library) is among the project's Debian dependencies, OpenCV writes rasters only, and the plots need
// nothing but polylines, polygons, circles and text.
#pragma once

#include <string>
#include <vector>

namespace whiskeye::figure {

struct Rgb {
  int r = 0;
  int g = 0;
  int b = 0;
};

struct Xy {
  double x = 0.0;
  double y = 0.0;
};

// One thing drawn. Sizes in px are the same in the PNG and the SVG (the SVG's user unit is a pixel).
struct FigureItem {
  enum class Kind { Polyline, Polygon, Disc, Marker, Tick, Text };
  Kind kind = Kind::Polyline;
  std::vector<Xy> points;  // world m; one point for Disc, Marker, Tick, Text
  Rgb colour;              // stroke (Polyline, Tick, unfilled Marker) or fill
  double size = 1.0;       // px: stroke width, marker radius, tick length, font size; Disc: radius in m
  bool filled = true;      // Marker: disc or ring
  double angle = 0.0;      // Tick: direction (rad, world frame)
  std::string text;        // Text
  int anchor = 0;          // Text: -1 starts at the point, 0 centred on it, 1 ends at it
  std::string cls;         // SVG class (what the item is: "wall", "experience", ...)
  std::string name;        // SVG data-name and <title> (e.g. a landmark's name); may be empty
};

class FigurePanel {
 public:
  explicit FigurePanel(std::string title) : title_(std::move(title)) {}

  void polyline(std::vector<Xy> pts, Rgb colour, double width_px, std::string cls, std::string name = "");
  void polygon(std::vector<Xy> pts, Rgb fill, std::string cls, std::string name = "");
  void disc(Xy centre, double radius_m, Rgb fill, std::string cls, std::string name = "");
  void marker(Xy at, double radius_px, Rgb colour, bool filled, std::string cls);
  void tick(Xy at, double angle, double length_px, Rgb colour, std::string cls);
  void text(Xy at, std::string text, Rgb colour, double size_px, std::string cls, int anchor = 0);

  // Axis labels name the frame: "x (m), world frame".
  void set_frame(std::string frame) { frame_ = std::move(frame); }
  // Extends the drawn area (e.g. to the arena's walls) beyond the items' own extent.
  void include(Xy p);

  const std::string& title() const { return title_; }
  const std::string& frame() const { return frame_; }
  const std::vector<FigureItem>& items() const { return items_; }
  // Bounding box of the items (and include()d points): min x, max x, min y, max y; false if empty.
  bool extent(double& x0, double& x1, double& y0, double& y1) const;

 private:
  std::string title_;
  std::string frame_ = "map frame";
  std::vector<FigureItem> items_;
  std::vector<Xy> extra_;
};

struct LegendEntry {
  enum class Kind { Line, Dot, Ring, Tick, Note };
  Kind kind = Kind::Note;
  Rgb colour;
  double size = 2.0;  // line width or dot radius, px
  std::string text;
};

// A colour scale in the legend: what the colours of `FigurePanel` items coloured by time_colour() mean.
struct ColourBar {
  std::string label;  // "time since the first pose (s)"
  double min = 0.0;
  double max = 1.0;
};

// Viridis-like colour at f in [0, 1] (dark blue → green → yellow): readable in grey, for colour blindness.
Rgb time_colour(double f);

class Figure {
 public:
  explicit Figure(std::string title) : title_(std::move(title)) {}
  FigurePanel& add_panel(std::string title);
  void legend(LegendEntry entry) { legend_.push_back(std::move(entry)); }
  void colour_bar(ColourBar bar) { bar_ = std::move(bar); has_bar_ = true; }
  // Every panel gets the same axes (the union of their extents): maps side by side compare at one scale.
  void share_axes(bool share) { share_axes_ = share; }

  // Each throws std::runtime_error naming the file if it cannot write it, or the figure if it cannot
  // be drawn: data not finite, or lying more than 1e9 times its extent from the origin.
  void write_png(const std::string& path) const;
  void write_svg(const std::string& path) const;

 private:
  std::string title_;
  std::vector<FigurePanel> panels_;
  std::vector<LegendEntry> legend_;
  ColourBar bar_;
  bool has_bar_ = false;
  bool share_axes_ = true;
};

}  // namespace whiskeye::figure

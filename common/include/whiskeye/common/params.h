// Loading YAML parameters into plain structs, strictly.
//
// Every module has one parameter struct with working defaults and a loader of the form
//   void load(const ParamNode& node, MyParams& p) { node.get("rate_hz", p.rate_hz, 1.0, 1000.0); ... }
// A key absent from the file keeps its default. A wrong type, a value out of range, a non-finite number
// (.nan, .inf: no parameter means them, and they slip through range checks or into geometry), or a
// key that no loader asked for (a typo) is a ParamError whose message names the file and the full
// key path. A key given twice in one map is refused at parse time, naming both lines (yaml-cpp would
// silently keep the first, so an override further down a file was ignored); so is a second YAML
// document (`---` after the first), which no loader would read. An integer is decimal or hex (0x15);
// one with a leading 0 (021: octal 17 to yaml-cpp, 21 to YAML 1.2) is refused, from the file or an override.
// dump() lists every parameter asked for, with its value and whether it came from the file, so a
// daemon can print exactly what it runs with. A command-line option that overrides a key goes in
// through set_override() before the loader runs: the loader checks it like a value from the file,
// and dump() shows the value in use, tagged with the option.
//
// yaml-cpp stays behind this header (only params.cpp includes it), so the algorithm libraries that
// load their parameters here never see YAML. get()/require() are instantiated in params.cpp for the
// types the loaders use: bool, the integer types, float, double, std::string and vectors of them (and
// vectors of vectors of double and int); another type is a link error naming ParamNode::get<T>: add
// it to the list at the end of params.cpp.
#pragma once

#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace YAML {
class Node;
}

namespace whiskeye {

class ParamError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class ParamNode {
 public:
  // Parses a YAML file; a missing or unparsable file is a ParamError naming it.
  static ParamNode from_file(const std::string& path);
  static ParamNode from_string(const std::string& yaml, const std::string& source = "<string>");
  // No file: every get() keeps its default.
  static ParamNode empty(const std::string& source = "<defaults>");

  // A nested map. A missing section is an empty node (defaults apply); a non-map is an error.
  ParamNode section(const std::string& key) const;
  // A list of maps (e.g. the walls of a world). A missing list is empty; a non-list is an error.
  std::vector<ParamNode> list(const std::string& key) const;
  bool has(const std::string& key) const;
  // A scalar's text as written ("0x10", "010"; "" when absent or not a scalar), for a loader that
  // checks how a value is spelt as well as what it is; get() still reads (and dump() lists) it.
  std::string text(const std::string& key) const;

  // The value of `path` (dotted, from the root: "can.interface") is `value`, given by `option`
  // ("--interface"), whatever the file says. Read by get() as a scalar from the file would be, so the
  // loader's type and range checks apply; a failing check names the option. Call before loading.
  // A path given a second time (two `--set` of one key, or `--set slam.mode=…` and `--mode`) is a
  // ParamError naming both options: the later would silently have won.
  void set_override(const std::string& path, const std::string& value, const std::string& option);

  // Optional scalar or list-of-scalars parameter: keeps `value` when the key is absent.
  template <typename T>
  void get(const std::string& key, T& value) const;
  // Same, then checks min <= value <= max.
  template <typename T>
  void get(const std::string& key, T& value, T min, T max) const;
  // Mandatory parameter: absent is an error.
  template <typename T>
  void require(const std::string& key, T& value) const;

  // Throws ParamError naming the first key in the document that no get/section/list asked for, or
  // the first override that no loader read (a misspelt `--set` key).
  void check_no_unknown_keys() const;
  // One line "path: value" per parameter asked for, "  (default)" where the file did not set it,
  // "  (--option)" where a command-line option did.
  std::string dump() const;
  const std::string& source() const;
  std::string path_of(const std::string& key) const;
  // Throws ParamError "<source>: '<path of key>' <what>", the source being the file, or the option
  // that overrides the key: for a loader's own checks of a value it read.
  [[noreturn]] void fail(const std::string& key, const std::string& what) const;

 private:
  struct State;
  ParamNode(std::shared_ptr<State> state, const YAML::Node& node, std::string prefix);

  YAML::Node lookup(const std::string& key) const;
  void mark_leaf(const std::string& key, const std::string& value, bool from_file) const;
  static std::string describe(const YAML::Node& node);

  template <typename T>
  static std::string to_text(const T& value);
  // True unless a floating-point number in `value` (a scalar or nested lists) is NaN or infinite.
  template <typename T>
  static bool all_finite(const T& value);

  std::shared_ptr<State> state_;
  std::shared_ptr<const YAML::Node> node_;  // this node's map (never null; shared by copies)
  std::string prefix_;
};

}  // namespace whiskeye

// Strict YAML parameters (see params.h): the only file that includes yaml-cpp.
#include "whiskeye/common/params.h"

#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdint>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <type_traits>

namespace whiskeye {

namespace {

// yaml-cpp keeps every pair of a map with a key given twice, and lookups return the first: an
// override further down a config would be ignored without a word. Refused, naming both lines.
void check_no_duplicate_keys(const YAML::Node& node, const std::string& path, const std::string& source, int depth) {
  // Deeper than any config; also stops at an alias that refers to a node containing it.
  if (depth > 64) throw ParamError(source + ": '" + path + "' is nested more than 64 levels deep");
  if (node.IsMap()) {
    std::map<std::string, int> lines;
    for (const auto& kv : node) {
      if (!kv.first.IsScalar()) continue;
      const std::string key = kv.first.Scalar();
      const int line = kv.first.Mark().line + 1;
      const std::string child = path.empty() ? key : path + "." + key;
      if (const auto [it, inserted] = lines.emplace(key, line); !inserted) {
        throw ParamError(source + ": duplicate key '" + child + "' on lines " + std::to_string(it->second) + " and " +
                         std::to_string(line) + " (only one value can count: remove one)");
      }
      check_no_duplicate_keys(kv.second, child, source, depth + 1);
    }
  } else if (node.IsSequence()) {
    for (std::size_t i = 0; i < node.size(); ++i) {
      check_no_duplicate_keys(node[i], path + "[" + std::to_string(i) + "]", source, depth + 1);
    }
  }
}

// Values (scalars, lists, maps) a config may hold. yaml-cpp's tree costs ~100 times the text it
// holds, so the bound is on the text's values before any tree is built: the largest file of the
// stack (a world with a long lighting.changes list) holds a few hundred.
constexpr long kMaxYamlValues = 100'000;

// What every config is refused for before its tree is built, by yaml-cpp's event parser, which reads
// the text once and expands nothing: an anchor (&name) or an alias (*name), naming its line (an
// alias stands for a copy of its anchor, and nested aliases expand exponentially: a few hundred
// bytes, billions of values in every walk of the tree); more than kMaxYamlValues values; a second
// document (`---` after the first), which the tree, built from the first alone, would leave unread.
class NoAnchors final : public YAML::EventHandler {
 public:
  explicit NoAnchors(const std::string& source) : source_(source) {}
  void OnDocumentStart(const YAML::Mark& mark) override {
    if (++documents_ > 1) {
      throw ParamError(source_ + ": line " + std::to_string(mark.line + 1) +
                       ": a second YAML document ('---'): a config is one document (what follows would be ignored)");
    }
  }
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark& mark, YAML::anchor_t anchor) override { check(mark, anchor); }
  void OnAlias(const YAML::Mark& mark, YAML::anchor_t) override { refuse(mark, "an alias (*name)"); }
  void OnScalar(const YAML::Mark& mark, const std::string&, YAML::anchor_t anchor, const std::string&) override {
    check(mark, anchor);
  }
  void OnSequenceStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t anchor,
                       YAML::EmitterStyle::value) override {
    check(mark, anchor);
  }
  void OnSequenceEnd() override {}
  void OnMapStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t anchor, YAML::EmitterStyle::value) override {
    check(mark, anchor);
  }
  void OnMapEnd() override {}
  void OnAnchor(const YAML::Mark& mark, const std::string& name) override { refuse(mark, "an anchor (&" + name + ")"); }

 private:
  void check(const YAML::Mark& mark, YAML::anchor_t anchor) {
    if (anchor != YAML::NullAnchor) refuse(mark, "an anchor");
    if (++values_ > kMaxYamlValues) {
      throw ParamError(source_ + ": line " + std::to_string(mark.line + 1) + ": more than " +
                       std::to_string(kMaxYamlValues) + " values in one file (no config of the stack needs so many)");
    }
  }
  long values_ = 0;
  int documents_ = 0;
  [[noreturn]] void refuse(const YAML::Mark& mark, const std::string& what) {
    throw ParamError(source_ + ": line " + std::to_string(mark.line + 1) + ": " + what +
                     ": YAML anchors and aliases are not accepted (write each value out where it is used)");
  }
  const std::string& source_;
};

// The one document of `yaml`, refused if it is not valid YAML, holds an anchor or an alias, or is
// followed by another.
YAML::Node load_plain_yaml(const std::string& yaml, const std::string& source) {
  try {
    std::istringstream in(yaml);
    YAML::Parser parser(in);
    NoAnchors handler(source);
    while (parser.HandleNextDocument(handler)) {
    }
    return YAML::Load(yaml);
  } catch (const YAML::Exception& e) {
    throw ParamError(source + ": not valid YAML: " + e.what());
  }
}

// An integer parameter, or a list (of lists) of them.
template <typename T>
struct IsIntegerParam : std::bool_constant<std::is_integral_v<T> && !std::is_same_v<T, bool>> {};
template <typename T>
struct IsIntegerParam<std::vector<T>> : IsIntegerParam<T> {};

// The first scalar of `node` (a scalar or nested lists) written with a leading 0 (021, -007):
// yaml-cpp reads an integer as C's streams do, in octal (021 is 17), where YAML 1.2 reads 21. Which one
// was meant cannot be known, so such an integer is refused; 0 itself, 0x15 (hex) and 21 are plain.
std::optional<YAML::Node> first_leading_zero(const YAML::Node& node) {
  if (node.IsSequence()) {
    for (const YAML::Node& item : node) {
      if (auto found = first_leading_zero(item)) return found;
    }
  } else if (node.IsScalar()) {
    const std::string& text = node.Scalar();
    const std::size_t digits = !text.empty() && (text[0] == '-' || text[0] == '+') ? 1 : 0;
    if (text.size() > digits + 1 && text[digits] == '0' && text[digits + 1] >= '0' && text[digits + 1] <= '9') {
      return node;
    }
  }
  return std::nullopt;
}

}  // namespace

struct ParamNode::State {
  std::string source;
  YAML::Node root;
  std::set<std::string> leaves;    // keys read as values: their whole subtree is known
  std::set<std::string> sections;  // maps and lists descended into: their children are checked
  std::vector<std::string> dump_lines;
  std::map<std::string, std::pair<std::string, std::string>> overrides;  // path -> (value, option)
};

ParamNode::ParamNode(std::shared_ptr<State> state, const YAML::Node& node, std::string prefix)
    : state_(std::move(state)), node_(std::make_shared<const YAML::Node>(node)), prefix_(std::move(prefix)) {}

ParamNode ParamNode::from_string(const std::string& yaml, const std::string& source) {
  auto state = std::make_shared<State>();
  state->source = source;
  state->root = load_plain_yaml(yaml, source);
  if (state->root.IsNull()) state->root = YAML::Node(YAML::NodeType::Map);
  if (!state->root.IsMap()) throw ParamError(source + ": the document must be a map of keys");
  check_no_duplicate_keys(state->root, "", source, 0);
  return ParamNode(state, state->root, "");
}

ParamNode ParamNode::from_file(const std::string& path) {
  auto state = std::make_shared<State>();
  state->source = path;
  std::ifstream file(path, std::ios::binary);
  if (!file) throw ParamError(path + ": cannot open the file");
  std::ostringstream text;
  text << file.rdbuf();  // an empty file sets text's failbit, and its string is empty: fine
  state->root = load_plain_yaml(text.str(), path);
  if (state->root.IsNull()) state->root = YAML::Node(YAML::NodeType::Map);
  if (!state->root.IsMap()) throw ParamError(path + ": the document must be a map of keys");
  check_no_duplicate_keys(state->root, "", path, 0);
  return ParamNode(state, state->root, "");
}

ParamNode ParamNode::empty(const std::string& source) { return from_string("{}", source); }

const std::string& ParamNode::source() const { return state_->source; }

std::string ParamNode::path_of(const std::string& key) const {
  return prefix_.empty() ? key : prefix_ + "." + key;
}

void ParamNode::set_override(const std::string& path, const std::string& value, const std::string& option) {
  const auto [it, inserted] = state_->overrides.try_emplace(path, value, option);
  if (!inserted) {
    throw ParamError(option + ": '" + path + "' is given twice on the command line (" + it->second.second + " and " +
                     option + "): only one value can count (remove one)");
  }
}

YAML::Node ParamNode::lookup(const std::string& key) const {
  if (const auto it = state_->overrides.find(path_of(key)); it != state_->overrides.end()) {
    return YAML::Node(it->second.first);
  }
  const YAML::Node& const_node = *node_;  // const: a lookup must not insert the key
  if (!const_node || !const_node.IsMap()) return YAML::Node();
  return const_node[key];
}

bool ParamNode::has(const std::string& key) const {
  const YAML::Node n = lookup(key);
  return n && !n.IsNull();
}

std::string ParamNode::text(const std::string& key) const {
  const YAML::Node n = lookup(key);
  return n && n.IsScalar() ? n.Scalar() : std::string();
}

std::string ParamNode::describe(const YAML::Node& node) {
  std::string text;
  if (node.IsScalar()) {
    text = "'" + node.Scalar() + "'";
  } else if (node.IsSequence()) {
    text = "a list";
  } else if (node.IsMap()) {
    text = "a map";
  } else {
    text = "nothing";
  }
  if (node.Mark().line >= 0) text += " (line " + std::to_string(node.Mark().line + 1) + ")";
  return text;
}

void ParamNode::fail(const std::string& key, const std::string& what) const {
  const auto it = state_->overrides.find(path_of(key));
  const std::string& source = it == state_->overrides.end() ? state_->source : it->second.second;
  throw ParamError(source + ": '" + path_of(key) + "' " + what);
}

void ParamNode::mark_leaf(const std::string& key, const std::string& value, bool from_file) const {
  const std::string path = path_of(key);
  state_->leaves.insert(path);
  const auto it = state_->overrides.find(path);
  const std::string tag = it != state_->overrides.end() ? "  (" + it->second.second + ")"
                          : from_file                     ? ""
                                                          : "  (default)";
  state_->dump_lines.push_back(path + ": " + value + tag);
}

ParamNode ParamNode::section(const std::string& key) const {
  const std::string path = path_of(key);
  state_->sections.insert(path);
  const YAML::Node n = lookup(key);
  if (!n || n.IsNull()) return ParamNode(state_, YAML::Node(YAML::NodeType::Map), path);
  if (!n.IsMap()) fail(key, "must be a map of keys, got " + describe(n));
  return ParamNode(state_, n, path);
}

std::vector<ParamNode> ParamNode::list(const std::string& key) const {
  const std::string path = path_of(key);
  state_->sections.insert(path);
  const YAML::Node n = lookup(key);
  std::vector<ParamNode> items;
  if (!n || n.IsNull()) return items;
  if (!n.IsSequence()) fail(key, "must be a list, got " + describe(n));
  for (std::size_t i = 0; i < n.size(); ++i) {
    const std::string item_path = path + "[" + std::to_string(i) + "]";
    if (!n[i].IsMap()) {
      throw ParamError(state_->source + ": '" + item_path + "' must be a map of keys, got " + describe(n[i]));
    }
    state_->sections.insert(item_path);
    items.push_back(ParamNode(state_, n[i], item_path));
  }
  return items;
}

namespace {

void check_node(const YAML::Node& node, const std::string& path, const std::set<std::string>& leaves,
                const std::set<std::string>& sections, const std::string& source) {
  if (node.IsMap()) {
    for (const auto& kv : node) {
      const std::string key = kv.first.Scalar();
      const std::string child = path.empty() ? key : path + "." + key;
      if (leaves.count(child)) continue;
      if (sections.count(child)) {
        check_node(kv.second, child, leaves, sections, source);
        continue;
      }
      throw ParamError(source + ": unknown key '" + child + "' (line " +
                       std::to_string(kv.first.Mark().line + 1) + ")");
    }
  } else if (node.IsSequence()) {
    for (std::size_t i = 0; i < node.size(); ++i) {
      check_node(node[i], path + "[" + std::to_string(i) + "]", leaves, sections, source);
    }
  }
}

}  // namespace

void ParamNode::check_no_unknown_keys() const {
  check_node(state_->root, "", state_->leaves, state_->sections, state_->source);
  for (const auto& [path, given] : state_->overrides) {
    if (!state_->leaves.count(path)) {
      throw ParamError(given.second + ": '" + path + "' is not a parameter");
    }
  }
}

std::string ParamNode::dump() const {
  std::string out;
  for (const auto& line : state_->dump_lines) out += line + "\n";
  return out;
}

// ---- the templates, and their instantiations for the types the loaders use ----

template <typename T>
std::string ParamNode::to_text(const T& value) {
  std::ostringstream out;
  out.precision(10);
  if constexpr (std::is_same_v<T, std::string>) {
    out << '"' << value << '"';
  } else if constexpr (std::is_same_v<T, bool>) {
    out << (value ? "true" : "false");
  } else if constexpr (std::is_arithmetic_v<T>) {
    out << +value;
  } else {
    out << '[';
    bool first = true;
    for (const auto& v : value) {
      out << (first ? "" : ", ") << to_text(v);
      first = false;
    }
    out << ']';
  }
  return out.str();
}

template <typename T>
bool ParamNode::all_finite(const T& value) {
  if constexpr (std::is_floating_point_v<T>) {
    return std::isfinite(value);
  } else if constexpr (std::is_arithmetic_v<T> || std::is_same_v<T, std::string>) {
    return true;
  } else {
    for (const auto& v : value) {
      if (!all_finite(v)) return false;
    }
    return true;
  }
}

template <typename T>
void ParamNode::get(const std::string& key, T& value) const {
  const YAML::Node n = lookup(key);
  if (!n || n.IsNull()) {
    mark_leaf(key, to_text(value), false);
    return;
  }
  if constexpr (IsIntegerParam<T>::value) {
    if (const auto zero = first_leading_zero(n)) {
      fail(key, "= " + describe(*zero) +
                    ": an integer with a leading 0 is ambiguous (octal or decimal): write it without the 0 (hex as 0x...)");
    }
  }
  try {
    value = n.as<T>();
  } catch (const YAML::Exception&) {
    fail(key, "has the wrong type: " + describe(n));
  }
  if (!all_finite(value)) fail(key, "= " + to_text(value) + " is not a finite number");
  mark_leaf(key, to_text(value), true);
}

template <typename T>
void ParamNode::get(const std::string& key, T& value, T min, T max) const {
  get(key, value);
  if (!(value >= min && value <= max)) {
    fail(key, "= " + to_text(value) + " is out of range [" + to_text(min) + ", " + to_text(max) + "]");
  }
}

template <typename T>
void ParamNode::require(const std::string& key, T& value) const {
  const YAML::Node n = lookup(key);
  if (!n || n.IsNull()) fail(key, "is required but missing");
  get(key, value);
}

// The types a loader may read (params.h). Each line instantiates get(), and for arithmetic types
// get() with a range; require() for each.
#define WHISKEYE_PARAM_TYPE(T)                                                         \
  template void ParamNode::get<T>(const std::string&, T&) const;                       \
  template void ParamNode::require<T>(const std::string&, T&) const;
#define WHISKEYE_PARAM_RANGE_TYPE(T) \
  WHISKEYE_PARAM_TYPE(T)             \
  template void ParamNode::get<T>(const std::string&, T&, T, T) const;

WHISKEYE_PARAM_RANGE_TYPE(int)
WHISKEYE_PARAM_RANGE_TYPE(unsigned)
WHISKEYE_PARAM_RANGE_TYPE(long)
WHISKEYE_PARAM_RANGE_TYPE(unsigned long)
WHISKEYE_PARAM_RANGE_TYPE(long long)
WHISKEYE_PARAM_RANGE_TYPE(unsigned long long)
WHISKEYE_PARAM_RANGE_TYPE(float)
WHISKEYE_PARAM_RANGE_TYPE(double)
WHISKEYE_PARAM_TYPE(bool)
WHISKEYE_PARAM_TYPE(std::string)
WHISKEYE_PARAM_TYPE(std::vector<int>)
WHISKEYE_PARAM_TYPE(std::vector<float>)
WHISKEYE_PARAM_TYPE(std::vector<double>)
WHISKEYE_PARAM_TYPE(std::vector<std::string>)
WHISKEYE_PARAM_TYPE(std::vector<std::vector<int>>)
WHISKEYE_PARAM_TYPE(std::vector<std::vector<double>>)

#undef WHISKEYE_PARAM_RANGE_TYPE
#undef WHISKEYE_PARAM_TYPE

}  // namespace whiskeye

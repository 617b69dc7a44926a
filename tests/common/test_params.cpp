#include "scratch.h"
#include "whiskeye/common/cli.h"
#include "whiskeye/common/params.h"

#include <gtest/gtest.h>
#include <gmock/gmock.h>

#include <fstream>

namespace whiskeye {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

struct Example {
  double rate_hz = 50.0;
  int cells = 21;
  bool enabled = true;
  std::string name = "default";
  std::vector<double> gains{1.0, 2.0};
  double inner = 0.5;
  bool operator==(const Example&) const = default;
};

void load(const ParamNode& n, Example& p) {
  n.get("rate_hz", p.rate_hz, 1.0, 1000.0);
  n.get("cells", p.cells, 3, 200);
  n.get("enabled", p.enabled);
  n.get("name", p.name);
  n.get("gains", p.gains);
  n.section("nested").get("inner", p.inner, 0.0, 1.0);
  n.check_no_unknown_keys();
}

std::string error_of(const std::string& yaml) {
  try {
    Example p;
    load(ParamNode::from_string(yaml, "test.yaml"), p);
  } catch (const ParamError& e) {
    return e.what();
  }
  return "";
}

TEST(Params, AbsentKeysKeepDefaults) {
  Example p;
  load(ParamNode::empty(), p);
  EXPECT_EQ(p, Example{});
}

TEST(Params, LoadsEveryType) {
  Example p;
  load(ParamNode::from_string("rate_hz: 100\ncells: 30\nenabled: false\nname: arena\n"
                              "gains: [3, 4.5]\nnested: {inner: 0.25}\n"),
       p);
  EXPECT_DOUBLE_EQ(p.rate_hz, 100.0);
  EXPECT_EQ(p.cells, 30);
  EXPECT_FALSE(p.enabled);
  EXPECT_EQ(p.name, "arena");
  EXPECT_EQ(p.gains, (std::vector<double>{3.0, 4.5}));
  EXPECT_DOUBLE_EQ(p.inner, 0.25);
}

TEST(Params, RejectsUnknownKeyByFullPath) {
  EXPECT_THAT(error_of("rate_hz: 10\nnested: {inner: 0.1, innr: 2}\n"),
              HasSubstr("test.yaml: unknown key 'nested.innr'"));
  EXPECT_THAT(error_of("rate_hzz: 10\n"), HasSubstr("unknown key 'rate_hzz' (line 1)"));
}

TEST(Params, RejectsWrongTypeNamingKeyAndLine) {
  const std::string e = error_of("rate_hz: 10\ncells: many\n");
  EXPECT_THAT(e, HasSubstr("test.yaml: 'cells' has the wrong type"));
  EXPECT_THAT(e, HasSubstr("'many' (line 2)"));
  EXPECT_THAT(error_of("cells: 2.5\n"), HasSubstr("'cells' has the wrong type"));
  EXPECT_THAT(error_of("nested: 3\n"), HasSubstr("'nested' must be a map"));
}

TEST(Params, RejectsOutOfRange) {
  EXPECT_THAT(error_of("rate_hz: 0\n"), HasSubstr("'rate_hz' = 0 is out of range [1, 1000]"));
  EXPECT_THAT(error_of("nested: {inner: 1.5}\n"), HasSubstr("'nested.inner' = 1.5 is out of range"));
}

TEST(Params, RejectsNonFiniteNumbersNamingTheKeyEvenWithoutARange) {
  EXPECT_THAT(error_of("rate_hz: .nan\n"), HasSubstr("'rate_hz' = nan is not a finite number"));
  EXPECT_THAT(error_of("rate_hz: .inf\n"), HasSubstr("'rate_hz' = inf is not a finite number"));
  EXPECT_THAT(error_of("rate_hz: -.inf\n"), HasSubstr("'rate_hz' = -inf is not a finite number"));
  // gains has no range: only the finiteness check stands between .nan and the loaded struct.
  EXPECT_THAT(error_of("gains: [1, .nan]\n"), HasSubstr("'gains' = [1, nan] is not a finite number"));
  EXPECT_THAT(error_of("gains: [.inf]\n"), HasSubstr("'gains' = [inf] is not a finite number"));
}

TEST(Params, RejectsNonFiniteNumbersInNestedLists) {
  const ParamNode n = ParamNode::from_string("points: [[0, 1], [2, .nan]]\n", "test.yaml");
  std::vector<std::vector<double>> points;
  try {
    n.get("points", points);
    FAIL() << "expected a ParamError";
  } catch (const ParamError& e) {
    EXPECT_THAT(e.what(), HasSubstr("'points'"));
    EXPECT_THAT(e.what(), HasSubstr("not a finite number"));
  }
}

TEST(Params, RequireFailsWhenMissing) {
  auto n = ParamNode::from_string("a: 1\n", "r.yaml");
  int a = 0;
  int b = 0;
  n.require("a", a);
  EXPECT_EQ(a, 1);
  try {
    n.require("b", b);
    FAIL() << "missing key accepted";
  } catch (const ParamError& e) {
    EXPECT_THAT(e.what(), HasSubstr("r.yaml: 'b' is required but missing"));
  }
}

TEST(Params, ListsOfMapsAreCheckedPerItem) {
  auto n = ParamNode::from_string("walls:\n  - {x: 1}\n  - {x: 2, colour: red}\n", "w.yaml");
  std::vector<double> xs;
  for (const auto& item : n.list("walls")) {
    double x = 0;
    item.get("x", x);
    xs.push_back(x);
  }
  EXPECT_EQ(xs, (std::vector<double>{1, 2}));
  try {
    n.check_no_unknown_keys();
    FAIL() << "unknown key accepted";
  } catch (const ParamError& e) {
    EXPECT_THAT(e.what(), HasSubstr("unknown key 'walls[1].colour'"));
  }
}

TEST(Params, DumpListsValuesAndDefaults) {
  Example p;
  load(ParamNode::from_string("cells: 30\n"), p);
  auto n = ParamNode::from_string("cells: 30\n");
  load(n, p);
  const std::string d = n.dump();
  EXPECT_THAT(d, HasSubstr("cells: 30\n"));
  EXPECT_THAT(d, HasSubstr("rate_hz: 50  (default)\n"));
  EXPECT_THAT(d, HasSubstr("nested.inner: 0.5  (default)\n"));
  EXPECT_THAT(d, HasSubstr("gains: [1, 2]  (default)\n"));
}

// yaml-cpp keeps the first of two equal keys: an override further down a config was ignored.
TEST(Params, ADuplicateKeyIsRefusedNamingBothLines) {
  EXPECT_THAT(error_of("rate_hz: 10\ncells: 30\nrate_hz: 20\n"),
              HasSubstr("test.yaml: duplicate key 'rate_hz' on lines 1 and 3"));
  EXPECT_THAT(error_of("nested:\n  inner: 0.1\n  inner: 0.9\n"),
              HasSubstr("duplicate key 'nested.inner' on lines 2 and 3"));
  EXPECT_THAT(error_of("nested: {inner: 0.1}\nnested: {inner: 0.2}\n"),
              HasSubstr("duplicate key 'nested' on lines 1 and 2"));
  EXPECT_THAT(error_of("items:\n  - {a: 1, a: 2}\n"), HasSubstr("duplicate key 'items[0].a' on lines 2 and 2"));
  EXPECT_EQ(error_of("rate_hz: 10\nnested: {inner: 0.1}\n"), "") << "equal keys in different maps are fine";
  const std::string path = whiskeye::testing::scratch_file("params_dup", ".yaml");
  std::ofstream(path) << "cells: 30\n# an override\ncells: 40\n";
  try {
    ParamNode::from_file(path);
    FAIL();
  } catch (const ParamError& e) {
    EXPECT_THAT(e.what(), HasSubstr(path + ": duplicate key 'cells' on lines 1 and 3"));
  }
}

// A command-line option over a key (whiskerd -i, slamd --mode): the loader reads it as it would the
// file's value, and the dump shows the value in use, tagged with the option.
TEST(Params, AnOverrideIsLoadedAndDumpedWithItsOption) {
  Example p;
  auto n = ParamNode::from_string("cells: 30\nname: file\n");
  n.set_override("name", "cli", "--name");
  n.set_override("nested.inner", "0.25", "--inner");
  load(n, p);
  n.check_no_unknown_keys();
  EXPECT_EQ(p.name, "cli");
  EXPECT_EQ(p.inner, 0.25);
  EXPECT_EQ(p.cells, 30);
  const std::string d = n.dump();
  EXPECT_THAT(d, HasSubstr("name: \"cli\"  (--name)\n"));
  EXPECT_THAT(d, HasSubstr("nested.inner: 0.25  (--inner)\n"));
  EXPECT_THAT(d, HasSubstr("cells: 30\n"));
  EXPECT_THAT(d, Not(HasSubstr("file")));
}

// What every program runs with (cli::read_config): the file, then the command line's overrides over
// it; no file is every default.
TEST(Params, AProgramsConfigIsTheFileThenTheCommandLinesOverrides) {
  const std::string path = whiskeye::testing::scratch_file("read_config", ".yaml");
  std::ofstream(path) << "cells: 30\nname: file\n";
  Example p;
  ParamNode n = cli::read_config(path, {{"name", "cli", "--name"}, {"nested.inner", "0.25", "--set"}});
  load(n, p);
  n.check_no_unknown_keys();
  EXPECT_EQ(p.cells, 30);
  EXPECT_EQ(p.name, "cli");
  EXPECT_EQ(p.inner, 0.25);
  EXPECT_THAT(n.dump(), HasSubstr("name: \"cli\"  (--name)\n"));
  Example defaults;
  ParamNode none = cli::read_config("");
  load(none, defaults);
  EXPECT_EQ(defaults.cells, Example{}.cells);
  EXPECT_THROW(cli::read_config(path + ".missing"), ParamError);
}

// `--set cells=5 --set cells=7` (or `--set slam.mode=… --mode …`): the later silently took over.
TEST(Params, AKeyTheCommandLineGivesTwiceIsRefusedNamingBothOptions) {
  try {
    cli::read_config("", {{"cells", "5", "--set"}, {"cells", "7", "--set"}});
    FAIL();
  } catch (const ParamError& e) {
    EXPECT_EQ(std::string(e.what()),
              "--set: 'cells' is given twice on the command line (--set and --set): only one value can count (remove one)");
  }
  auto n = ParamNode::empty();
  n.set_override("name", "a", "--set");
  EXPECT_THROW(
      {
        try {
          n.set_override("name", "b", "--name");
        } catch (const ParamError& e) {
          EXPECT_THAT(e.what(), HasSubstr("--name: 'name' is given twice on the command line (--set and --name)"));
          throw;
        }
      },
      ParamError);
  Example p;
  load(n, p);
  EXPECT_EQ(p.name, "a") << "the refused one changed nothing";
}

TEST(Params, AnOverrideFailingTheLoadersCheckNamesTheOption) {
  auto range = ParamNode::empty();
  range.set_override("rate_hz", "5000", "--rate");
  try {
    Example p;
    load(range, p);
    FAIL();
  } catch (const ParamError& e) {
    EXPECT_THAT(e.what(), HasSubstr("--rate: 'rate_hz' = 5000 is out of range"));
  }
  auto type = ParamNode::empty();
  type.set_override("cells", "many", "--cells");
  try {
    Example p;
    load(type, p);
    FAIL();
  } catch (const ParamError& e) {
    EXPECT_THAT(e.what(), HasSubstr("--cells: 'cells' has the wrong type: 'many'"));
  }
}

// An override of a key no loader reads (a misspelt `slamd --set` key) is an error naming it.
TEST(Params, AnOverrideNoLoaderReadsIsAnErrorNamingIt) {
  Example p;
  auto n = ParamNode::empty();
  n.set_override("nested.outer", "1", "--set");
  try {
    load(n, p);  // load() ends with check_no_unknown_keys()
    FAIL();
  } catch (const ParamError& e) {
    EXPECT_THAT(e.what(), HasSubstr("--set: 'nested.outer' is not a parameter"));
  }
}

// Nine lists of nine aliases of the list before: 420 bytes that expand to 9^9 scalars.
std::string alias_bomb() {
  std::string yaml = "a: &a [x, x, x, x, x, x, x, x, x]\n";
  for (char c = 'b'; c <= 'i'; ++c) {
    const char prev = static_cast<char>(c - 1);
    yaml += std::string(1, c) + ": &" + c + " [";
    for (int k = 0; k < 9; ++k) yaml += std::string(k ? ", " : "") + "*" + prev;
    yaml += "]\n";
  }
  return yaml;
}

TEST(Params, AnAnchorOrAnAliasIsRefusedNamingItsLineBeforeAnythingIsExpanded) {
  EXPECT_THAT(error_of("rate_hz: 10\ncells: &c 30\n"),
              HasSubstr("test.yaml: line 2: an anchor (&c): YAML anchors and aliases are not accepted"));
  EXPECT_THAT(error_of("base: &base {inner: 0.1}\nnested:\n  <<: *base\n"), HasSubstr("line 1: an anchor (&base)"));
  EXPECT_THAT(error_of("nested:\n  - x\n  - &item {a: 1}\n"), HasSubstr("line 3: an anchor (&item)"));
  EXPECT_THAT(error_of("a: *nothing\n"), HasSubstr("test.yaml: not valid YAML")) << "an alias of no anchor";
  EXPECT_NO_THROW(ParamNode::from_string("url: http://host/a&b*c\nglob: '*.yaml'\n", "test.yaml"))
      << "& and * inside a value are plain text";

  const std::string path = whiskeye::testing::scratch_file("params_bomb", ".yaml");
  std::ofstream(path) << alias_bomb();
  try {
    ParamNode::from_file(path);
    FAIL();
  } catch (const ParamError& e) {
    EXPECT_EQ(std::string(e.what()), path + ": line 1: an anchor (&a): YAML anchors and aliases are not accepted "
                                            "(write each value out where it is used)");
  }
}

// yaml-cpp reads the first document of a file: a `---` and a second map after it (`can: {interface:
// vcan9}`) were ignored without a word. Any second document, even an empty one, is refused.
TEST(Params, ASecondYamlDocumentIsRefusedNamingItsLine) {
  EXPECT_EQ(error_of("cells: 30\n---\ncells: 40\n"),
            "test.yaml: line 2: a second YAML document ('---'): a config is one document (what follows would be "
            "ignored)");
  EXPECT_THAT(error_of("cells: 30\n...\n---\nrate_hz: 5\n"), HasSubstr("test.yaml: line 3: a second YAML document"));
  EXPECT_THAT(error_of("cells: 30\n--- # empty\n"), HasSubstr("line 2: a second YAML document"));
  EXPECT_EQ(error_of("# a comment\n---\ncells: 30\n...\n"), "") << "one document, with its markers";
  const std::string path = whiskeye::testing::scratch_file("params_two_docs", ".yaml");
  std::ofstream(path) << "name: first\n---\nname: second\n";
  try {
    ParamNode::from_file(path);
    FAIL();
  } catch (const ParamError& e) {
    EXPECT_THAT(e.what(), HasSubstr(path + ": line 2: a second YAML document ('---')"));
  }
}

// yaml-cpp reads an integer in C's bases: 021 was 17 (YAML 1.2 says 21), from the file and from a
// --set alike. A leading 0 is refused; hex, which the CAN ids use, is kept.
TEST(Params, AnIntegerWithALeadingZeroIsRefusedAndHexIsRead) {
  EXPECT_EQ(error_of("cells: 021\n"), "test.yaml: 'cells' = '021' (line 1): an integer with a leading 0 is ambiguous "
                                        "(octal or decimal): write it without the 0 (hex as 0x...)");
  EXPECT_THAT(error_of("cells: -007\n"), HasSubstr("'cells' = '-007' (line 1): an integer with a leading 0"));
  EXPECT_THAT(error_of("cells: '021'\n"), HasSubstr("'cells' = '021' (line 1): an integer with a leading 0"));
  EXPECT_EQ(error_of("rate_hz: 010.5\nnested: {inner: 0.5}\n"), "") << "a float's leading 0 is plain decimal";
  Example p;
  load(ParamNode::from_string("cells: 0x15\n"), p);
  EXPECT_EQ(p.cells, 21);

  auto n = ParamNode::empty();
  n.set_override("cells", "021", "--set");
  try {
    load(n, p);
    FAIL();
  } catch (const ParamError& e) {
    EXPECT_EQ(std::string(e.what()), "--set: 'cells' = '021': an integer with a leading 0 is ambiguous (octal or "
                                     "decimal): write it without the 0 (hex as 0x...)");
  }

  std::vector<std::vector<int>> grid{{1}};
  const auto lists = ParamNode::from_string("grid: [[1, 2], [3, 08]]\n", "test.yaml");
  try {
    lists.get("grid", grid);
    FAIL();
  } catch (const ParamError& e) {
    EXPECT_THAT(e.what(), HasSubstr("'grid' = '08' (line 1): an integer with a leading 0"));
  }
  int zero = 5;
  ParamNode::from_string("zero: 0\n").get("zero", zero);
  EXPECT_EQ(zero, 0);
}

TEST(Params, FileErrorsNameTheFile) {
  try {
    ParamNode::from_file("/nonexistent/robot.yaml");
    FAIL();
  } catch (const ParamError& e) {
    EXPECT_THAT(e.what(), HasSubstr("/nonexistent/robot.yaml: cannot open"));
  }
  const std::string path = whiskeye::testing::scratch_file("params_bad", ".yaml");
  std::ofstream(path) << "a: [1, 2\n";
  try {
    ParamNode::from_file(path);
    FAIL();
  } catch (const ParamError& e) {
    EXPECT_THAT(e.what(), HasSubstr(path + ": not valid YAML"));
  }
}

}  // namespace
}  // namespace whiskeye

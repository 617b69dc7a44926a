// The world file writer, beside the loader (world.h): writes the `world:` document of
// docs/simulator.md with yaml-cpp's emitter. Sections are block maps, every item of a list a flow
// map on one line, and each number is written at the decimals its caller gives, so that a generated
// file says what was drawn to the digit and loads back to the values the generator checked.
// Pure: returns the text; the caller writes it. No YAML type in this header (the emitter is private).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <variant>
#include <vector>

namespace whiskeye::sim {

// `value` at `decimals` decimals, as a world file writes numbers ("-0.0000" is written "0.0000").
std::string format_decimal(double value, int decimals);

class WorldWriter {
 public:
  struct Decimal {
    double value = 0.0;
    int decimals = 4;
  };
  // A scalar; a string is written plain (names, enumerations).
  using Scalar = std::variant<Decimal, int64_t, std::string, bool>;
  using Scalars = std::vector<Scalar>;
  // One field of a flow map: a scalar, a list [a, b], or a list of lists [[a, b], [c, d]].
  struct Field {
    std::string key;
    std::variant<Scalar, Scalars, std::vector<Scalars>> value;
  };
  using Entry = std::vector<Field>;  // a flow map, fields in order

  // `comment`: lines written as "# line" before the document (a header saying how it was made).
  explicit WorldWriter(const std::string& comment);
  ~WorldWriter();
  WorldWriter(const WorldWriter&) = delete;
  WorldWriter& operator=(const WorldWriter&) = delete;

  // In the current map (`world:`, or a section): `key: value`.
  void scalar(const std::string& key, const Scalar& value);
  // `key: {a: 1, b: [2, 3]}` on one line.
  void entry(const std::string& key, const Entry& value);
  // `key:` and one `- {...}` line per item.
  void list(const std::string& key, const std::vector<Entry>& items);
  // `key: [{...}, {...}]` on one line (short lists: lighting changes, faults).
  void flow_list(const std::string& key, const std::vector<Entry>& items);
  // `key: [a, b]`.
  void scalars(const std::string& key, const Scalars& values);
  // `key:` opening a block map (lighting, faults) until end_section().
  void begin_section(const std::string& key);
  void end_section();

  // The document, ending in a newline. Throws std::logic_error if a section is still open.
  std::string text();

 private:
  struct Emitter;
  std::unique_ptr<Emitter> out_;
  int open_sections_ = 0;
};

}  // namespace whiskeye::sim

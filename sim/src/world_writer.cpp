// World file writer (see world_writer.h): yaml-cpp's emitter.
#include "whiskeye/sim/world_writer.h"

#include <yaml-cpp/yaml.h>

#include <cstdio>
#include <stdexcept>

namespace whiskeye::sim {

std::string format_decimal(double value, int decimals) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, value);
  // "-0.0000" reads badly and is the same number.
  if (std::string(buf).find_first_not_of("-0.") == std::string::npos && buf[0] == '-') return buf + 1;
  return buf;
}

struct WorldWriter::Emitter {
  YAML::Emitter yaml;
};

namespace {

void emit(YAML::Emitter& out, const WorldWriter::Scalar& s) {
  if (const auto* d = std::get_if<WorldWriter::Decimal>(&s)) {
    out << format_decimal(d->value, d->decimals);
  } else if (const auto* i = std::get_if<int64_t>(&s)) {
    out << *i;
  } else if (const auto* t = std::get_if<std::string>(&s)) {
    out << *t;
  } else {
    out << std::get<bool>(s);
  }
}

void emit(YAML::Emitter& out, const WorldWriter::Scalars& v) {
  out << YAML::Flow << YAML::BeginSeq;
  for (const WorldWriter::Scalar& s : v) emit(out, s);
  out << YAML::EndSeq;
}

void emit(YAML::Emitter& out, const WorldWriter::Entry& e) {
  out << YAML::Flow << YAML::BeginMap;
  for (const WorldWriter::Field& f : e) {
    out << YAML::Key << f.key << YAML::Value;
    if (const auto* s = std::get_if<WorldWriter::Scalar>(&f.value)) {
      emit(out, *s);
    } else if (const auto* v = std::get_if<WorldWriter::Scalars>(&f.value)) {
      emit(out, *v);
    } else {
      out << YAML::Flow << YAML::BeginSeq;
      for (const WorldWriter::Scalars& inner : std::get<std::vector<WorldWriter::Scalars>>(f.value)) emit(out, inner);
      out << YAML::EndSeq;
    }
  }
  out << YAML::EndMap;
}

}  // namespace

WorldWriter::WorldWriter(const std::string& comment) : out_(std::make_unique<Emitter>()) {
  if (!comment.empty()) out_->yaml << YAML::Comment(comment);
  out_->yaml << YAML::BeginMap << YAML::Key << "world" << YAML::Value << YAML::BeginMap;
}

WorldWriter::~WorldWriter() = default;

void WorldWriter::scalar(const std::string& key, const Scalar& value) {
  out_->yaml << YAML::Key << key << YAML::Value;
  emit(out_->yaml, value);
}

void WorldWriter::entry(const std::string& key, const Entry& value) {
  out_->yaml << YAML::Key << key << YAML::Value;
  emit(out_->yaml, value);
}

void WorldWriter::list(const std::string& key, const std::vector<Entry>& items) {
  out_->yaml << YAML::Key << key << YAML::Value << YAML::BeginSeq;
  for (const Entry& e : items) emit(out_->yaml, e);
  out_->yaml << YAML::EndSeq;
}

void WorldWriter::flow_list(const std::string& key, const std::vector<Entry>& items) {
  out_->yaml << YAML::Key << key << YAML::Value << YAML::Flow << YAML::BeginSeq;
  for (const Entry& e : items) emit(out_->yaml, e);
  out_->yaml << YAML::EndSeq;
}

void WorldWriter::scalars(const std::string& key, const Scalars& values) {
  out_->yaml << YAML::Key << key << YAML::Value;
  emit(out_->yaml, values);
}

void WorldWriter::begin_section(const std::string& key) {
  out_->yaml << YAML::Key << key << YAML::Value << YAML::BeginMap;
  ++open_sections_;
}

void WorldWriter::end_section() {
  if (open_sections_ == 0) throw std::logic_error("WorldWriter: end_section() without a section");
  out_->yaml << YAML::EndMap;
  --open_sections_;
}

std::string WorldWriter::text() {
  if (open_sections_ != 0) throw std::logic_error("WorldWriter: a section is still open");
  out_->yaml << YAML::EndMap << YAML::EndMap;
  if (!out_->yaml.good()) throw std::logic_error("WorldWriter: " + out_->yaml.GetLastError());
  return std::string(out_->yaml.c_str()) + "\n";
}

}  // namespace whiskeye::sim

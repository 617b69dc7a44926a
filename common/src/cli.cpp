// The command-line convention shared by every program (whiskeye/common/cli.h).
#include "whiskeye/common/cli.h"
#include "whiskeye/common/log.h"

#include "whiskeye/common/output_file.h"
#include "whiskeye/common/params.h"

#include <cstdio>
#include <iostream>

namespace whiskeye::cli {

Program::Program(std::string name, const std::string& description) : name_(std::move(name)), app_(description, name_) {
  app_.set_version_flag("--version", name_ + " " + version(), "print \"" + name_ + " <version>\" and exit");
}

CLI::Option* Program::add_config(std::string& path, const std::string& what) {
  return app_.add_option("-c,--config", path, what)->check(CLI::ExistingFile);
}

CLI::Option* Program::add_print_config(bool& flag) {
  print_config_ = &flag;
  return app_.add_flag("--print-config", flag,
                       "print every parameter in use (command-line overrides included) and exit");
}

bool Program::print_config(const std::string& parameters) const {
  if (print_config_ == nullptr || !*print_config_) return false;
  std::cout << parameters;
  return true;
}

ParamNode read_config(const std::string& path, const std::vector<Override>& overrides) {
  ParamNode root = path.empty() ? ParamNode::empty() : ParamNode::from_file(path);
  for (const Override& o : overrides) root.set_override(o.key, o.value, o.option);
  return root;
}

CLI::Option* Program::add_lcm_url(std::string& url) {
  return app_.add_option("--lcm-url", url, "LCM URL (default: $LCM_DEFAULT_URL, or LCM's default)");
}

CLI::Option* Program::add_output(std::string& path, const std::string& what) {
  return app_.add_option("-o,--output", path, what);
}

void refuse_output_onto_input(const std::string& output_option, const std::string& output,
                              const std::vector<InputFile>& inputs) {
  for (const InputFile& in : inputs) {
    if (in.path.empty() || !same_regular_file(output, in.path)) continue;
    throw UsageError(output_option + " " + output + " is the file given to " + in.option + " (" + in.path +
                     "): writing it would destroy it");
  }
}

void refuse_unwritable_output(const std::string& option, const std::string& path) {
  if (const std::string why = output_file_problem(path); !why.empty()) throw UsageError(option + " " + path + ": " + why);
}

void Program::error(const std::string& reason) const {
  std::string line = reason;
  for (std::size_t at = line.find('\n'); at != std::string::npos; at = line.find('\n', at)) {
    line.replace(at, 1, at + 1 == line.size() ? "" : "; ");
  }
  log_error(name_ + ": " + line);  // priority 3 in the journal (common/log.h)
}

int Program::run(int argc, char** argv, const std::function<int()>& body) {
  try {
    app_.parse(argc, argv);
  } catch (const CLI::Success& e) {  // --help, --version
    return app_.exit(e);
  } catch (const CLI::ParseError& e) {
    error(std::string(e.what()) + " (see --help)");
    return kExitUsage;
  }
  try {
    return body();
  } catch (const CLI::ParseError& e) {
    error(std::string(e.what()) + " (see --help)");
    return kExitUsage;
  } catch (const UsageError& e) {
    error(e.what());
    return kExitUsage;
  } catch (const ParamError& e) {
    error(std::string("bad config: ") + e.what());
    return kExitUsage;
  } catch (const std::exception& e) {
    error(e.what());
    return kExitFailure;
  }
}

}  // namespace whiskeye::cli

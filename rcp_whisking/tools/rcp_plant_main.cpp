// rcp-plant: runs the whisking controller against the plant model (placeholder until implemented).
#include <CLI/CLI.hpp>
int main(int argc, char** argv) {
  CLI::App app{"rcp-plant"};
  CLI11_PARSE(app, argc, argv);
  return 0;
}

// `farm`: the render farm's command line.
#include <CLI/CLI.hpp>

int main(int argc, char** argv) {
  CLI::App app{"farm: render farm batch service"};
  app.require_subcommand(1);
  CLI11_PARSE(app, argc, argv);
  return 0;
}

// viewpose: find known objects in one depth frame and estimate their 6-DoF poses from CAD models.
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <exception>

#include <fmt/format.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include "commands.hpp"
#include "process_memory.hpp"
#include "viewpose/core/error.hpp"
#include "viewpose/core/threads.hpp"

int main(int argc, char** argv) {
  viewpose::cli::keep_freed_memory();
  // Messages go to stderr so that stdout carries only results.
  // A write past the file-size limit (ulimit -f) fails with EFBIG, reported like a full disk, instead
  // of killing the process half way through.
  std::signal(SIGXFSZ, SIG_IGN);
  auto logger = spdlog::stderr_color_mt("viewpose");
  logger->set_pattern("viewpose: %l: %v");
  spdlog::set_default_logger(logger);

  CLI::App app{"viewpose " VIEWPOSE_VERSION
               ": find known objects in one depth frame and estimate their 6-DoF poses from CAD models"};
  app.set_version_flag("--version", std::string(VIEWPOSE_VERSION));
  app.require_subcommand(1);
  app.footer("Exit status: 0 done; 1 bad input or a failure (one line on stderr says which); 2 a usage error "
             "(an unknown option, a missing argument or file).");
  // Accepted before or after the command: `viewpose --threads 1 bop ...` or `viewpose bop ... --threads 1`.
  app.fallthrough();
  app.add_option("--threads", "Threads for every parallel stage (default: every core); results do not depend on it")
      ->check(CLI::Range(1, 1024))
      ->each([](const std::string& n) { viewpose::set_thread_count(std::stoi(n)); });
  int exit_code = 0;
  viewpose::cli::add_info_command(app, exit_code);
  viewpose::cli::add_demo_command(app, exit_code);
  viewpose::cli::add_simulate_command(app, exit_code);
  viewpose::cli::add_db_command(app, exit_code);
  viewpose::cli::add_recognize_command(app, exit_code);
  viewpose::cli::add_bop_command(app, exit_code);
  viewpose::cli::add_eval_command(app, exit_code);
  viewpose::cli::add_bench_command(app, exit_code);
  viewpose::cli::add_live_command(app, exit_code);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help and --version end well; every other parse error is a usage error: exit status 2, the
    // convention of command-line tools (CLI11's own codes, 105 for a missing file, say nothing).
    const int cli_code = app.exit(e);
    return cli_code == 0 ? 0 : 2;
  } catch (const viewpose::Error& e) {
    fmt::print(stderr, "viewpose: error: {}\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    fmt::print(stderr, "viewpose: error: {}\n", e.what());
    return 1;
  }
  // Results on stdout that did not all arrive (a full disk, a closed pipe) are a failure, not a success.
  if (std::fflush(stdout) != 0 || std::ferror(stdout)) {
    fmt::print(stderr, "viewpose: error: cannot write to standard output: {}\n", std::strerror(errno));
    return 1;
  }
  return exit_code;
}

#pragma once
// One function per subcommand: it adds itself to the app and, when chosen, runs and sets the exit
// code. Errors are thrown as viewpose::Error and printed as one line by main().
#include <filesystem>

#include <CLI/CLI.hpp>

#include "viewpose/io/inspect.hpp"
#include "viewpose/recognize/recognizer.hpp"

namespace viewpose::cli {

void add_info_command(CLI::App& app, int& exit_code);
void add_demo_command(CLI::App& app, int& exit_code);
void add_simulate_command(CLI::App& app, int& exit_code);
void add_db_command(CLI::App& app, int& exit_code);
void add_eval_command(CLI::App& app, int& exit_code);
void add_bench_command(CLI::App& app, int& exit_code);
void add_recognize_command(CLI::App& app, int& exit_code);
void add_bop_command(CLI::App& app, int& exit_code);
void add_live_command(CLI::App& app, int& exit_code);

/// The detections and times in words, as `viewpose recognize` prints them; where none is found,
/// the most confident pose below `min_score` (the confidence bound the recognizer used).
void print_recognition(const Recognition& r, double min_score);

/// Prints what inspect_file found, as `viewpose info` shows it.
void print_file_info(const std::filesystem::path& path, const FileInfo& info);

}  // namespace viewpose::cli

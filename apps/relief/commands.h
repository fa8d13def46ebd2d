#pragma once
#include <string>
#include <vector>

namespace relief::cli {

// Each returns the process exit code; errors are printed as one line on stderr.
int run_build(const std::vector<std::string>& args);
int run_info(const std::vector<std::string>& args);
int run_verify(const std::vector<std::string>& args);
int run_upgrade(const std::vector<std::string>& args);
int run_split(const std::vector<std::string>& args);
int run_export(const std::vector<std::string>& args);
int run_process(const std::vector<std::string>& args);
int run_fuse(const std::vector<std::string>& args);
int run_detect(const std::vector<std::string>& args);
int run_render(const std::vector<std::string>& args);
int run_serve(const std::vector<std::string>& args);
int run_view(const std::vector<std::string>& args);

// Prints "relief: <message>" on stderr and returns 1.
int report_error(const std::string& message);
bool wants_help(const std::vector<std::string>& args);
// Prints a command's help on stdout; returns exit code 0.
int print_help(const char* text);

}  // namespace relief::cli

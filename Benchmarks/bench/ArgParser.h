// SPDX-License-Identifier: BSD-3-Clause
//
// The command-line parser of the benchmark programs (mcvol-bench,
// mcvol-pyramid, mcvol-accuracy): a table of options, each with its name, the
// number of values it takes, how the help names them, one line of help and
// the function that stores them.

#pragma once

#include <functional>
#include <string>
#include <vector>

namespace mcvolbench
{
/// An option's values, as given on the command line.
using Args = std::vector<std::string>;

class ArgParser
{
public:
  /// Receives an option's values (as many as the option takes, none for a flag).
  using Handler = std::function<void(const Args& values)>;

  /// `program` heads the usage line; `epilog`, if any, follows the options in the help.
  explicit ArgParser(std::string program, std::string epilog = "");

  /// Declares an option: `name` ("--size"), the number of values it takes
  /// (0: a flag), their names in the help ("W H"), one line of help, and the
  /// handler that stores them (it may throw std::invalid_argument).
  ArgParser& add(
    const std::string& name, int count, const std::string& values, const std::string& help, Handler handler);

  /// Runs the handler of each option in argv[1..argc-1], in order. Throws
  /// std::invalid_argument on an unknown option or one short of values;
  /// "--help" or "-h" prints help() to stdout and exits with status 0.
  void parse(int argc, char** argv) const;

  /// The usage line and every option with its values and help.
  std::string help() const;
  void printHelp() const;

private:
  struct Option
  {
    std::string name;
    int count = 0;
    std::string values;
    std::string help;
    Handler handler;
  };
  std::string Program;
  std::string Epilog;
  std::vector<Option> Options;
};

/// The non-empty items of a `sep`-separated list ("a,b,,c": a, b, c).
std::vector<std::string> splitList(const std::string& s, char sep = ',');
/// A comma-separated list of integers (std::stoi each).
std::vector<int> splitInts(const std::string& s);
/// A comma-separated list of reals (std::stod each).
std::vector<double> splitDoubles(const std::string& s);
} // namespace mcvolbench

// SPDX-License-Identifier: BSD-3-Clause

#include "ArgParser.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace mcvolbench
{
ArgParser::ArgParser(std::string program, std::string epilog)
  : Program(std::move(program))
  , Epilog(std::move(epilog))
{
}

ArgParser& ArgParser::add(
  const std::string& name, int count, const std::string& values, const std::string& help, Handler handler)
{
  this->Options.push_back({ name, count, values, help, std::move(handler) });
  return *this;
}

void ArgParser::parse(int argc, char** argv) const
{
  for (int i = 1; i < argc; ++i)
  {
    const std::string a = argv[i];
    if (a == "--help" || a == "-h")
    {
      this->printHelp();
      std::exit(0);
    }
    const auto it =
      std::find_if(this->Options.begin(), this->Options.end(), [&](const Option& o) { return o.name == a; });
    if (it == this->Options.end())
    {
      throw std::invalid_argument("unknown option " + a);
    }
    if (i + it->count >= argc)
    {
      throw std::invalid_argument(a + " needs " + std::to_string(it->count) + " value(s)");
    }
    const std::vector<std::string> values(argv + i + 1, argv + i + 1 + it->count);
    i += it->count;
    it->handler(values);
  }
}

std::string ArgParser::help() const
{
  std::ostringstream s;
  s << "usage: " << this->Program << " [option...]\n\noptions:\n";
  // The help column starts after the widest option that fits in kColumn;
  // a wider one puts its help on the next line.
  const size_t kColumn = 28;
  size_t width = 10; // "--help, -h"
  for (const Option& o : this->Options)
  {
    const size_t w = o.name.size() + (o.values.empty() ? 0 : o.values.size() + 1);
    width = w <= kColumn ? std::max(width, w) : width;
  }
  const auto line = [&](const std::string& head, const std::string& help)
  {
    s << "  " << head;
    if (head.size() > width)
    {
      s << "\n" << std::string(width + 2, ' ');
    }
    else
    {
      s << std::string(width - head.size(), ' ');
    }
    s << "  " << help << "\n";
  };
  for (const Option& o : this->Options)
  {
    line(o.name + (o.values.empty() ? "" : " " + o.values), o.help);
  }
  line("--help, -h", "this text");
  if (!this->Epilog.empty())
  {
    s << "\n" << this->Epilog << "\n";
  }
  return s.str();
}

void ArgParser::printHelp() const
{
  std::fputs(this->help().c_str(), stdout);
}

std::vector<std::string> splitList(const std::string& s, char sep)
{
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, sep))
  {
    if (!item.empty())
    {
      out.push_back(item);
    }
  }
  return out;
}

std::vector<int> splitInts(const std::string& s)
{
  std::vector<int> out;
  for (const std::string& t : splitList(s))
  {
    out.push_back(std::stoi(t));
  }
  return out;
}

std::vector<double> splitDoubles(const std::string& s)
{
  std::vector<double> out;
  for (const std::string& t : splitList(s))
  {
    out.push_back(std::stod(t));
  }
  return out;
}
} // namespace mcvolbench

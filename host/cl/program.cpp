// Building OpenCL programs as specialisations, with readable build errors and an in-process cache.
#include "cl/program.hpp"

#include <algorithm>
#include <cstdio>
#include <regex>
#include <sstream>

#include "cl/compiler_output.hpp"
#include "cl/error.hpp"
#include "cl/kernel_sources.hpp"

namespace mipnerf::ocl {

BuildOptions& BuildOptions::define(const std::string& name, const std::string& value) {
  defines_[name] = value;
  return *this;
}

BuildOptions& BuildOptions::define(const std::string& name, long long value) {
  return define(name, std::to_string(value));
}

BuildOptions& BuildOptions::define_float(const std::string& name, float value) {
  char text[64];
  std::snprintf(text, sizeof(text), "%.9gf", static_cast<double>(value));
  std::string literal = text;
  // "1f" is not a valid literal; make sure a decimal point or exponent is present.
  if (literal.find_first_of(".eEn") == std::string::npos) literal.insert(literal.size() - 1, ".0");
  return define(name, literal);
}

BuildOptions& BuildOptions::flag(const std::string& compiler_flag) {
  for (const auto& f : flags_) {
    if (f == compiler_flag) return *this;
  }
  flags_.push_back(compiler_flag);
  return *this;
}

BuildOptions& BuildOptions::merge(const BuildOptions& other) {
  for (const auto& [name, value] : other.defines_) defines_[name] = value;
  for (const auto& f : other.flags_) flag(f);
  return *this;
}

std::string BuildOptions::str() const {
  std::string out;
  for (const auto& [name, value] : defines_) {
    out += out.empty() ? "" : " ";
    out += "-D" + name + "=" + value;
  }
  for (const auto& f : flags_) {
    out += out.empty() ? "" : " ";
    out += f;
  }
  return out;
}

std::vector<SourceFile> embedded_sources(const std::vector<std::string>& names) {
  std::vector<SourceFile> files;
  for (const auto& name : names) files.push_back({name, std::string(kernel_source(name))});
  return files;
}

::cl::Kernel& Program::kernel(const std::string& name) {
  auto found = kernels_.find(name);
  if (found != kernels_.end()) return found->second;
  cl_int status = CL_SUCCESS;
  ::cl::Kernel kernel(program_, name.c_str(), &status);
  check(status, "clCreateKernel(" + name + ") in " + label_);
  return kernels_.emplace(name, std::move(kernel)).first->second;
}

std::string assemble_source(const std::vector<SourceFile>& files, const BuildOptions& options) {
  std::string text = "/* mipnerf-cl program; build options: " + options.str() + " */\n";
  for (const auto& file : files) {
    text += "#line 1 \"" + file.name + "\"\n";
    text += file.text;
    if (text.empty() || text.back() != '\n') text += '\n';
  }
  return text;
}

unsigned long long fnv1a_64(const std::string& text) {
  unsigned long long hash = 14695981039346656037ull;
  for (unsigned char c : text) {
    hash ^= c;
    hash *= 1099511628211ull;
  }
  return hash;
}

namespace {

std::string label_of(const std::vector<SourceFile>& files, const BuildOptions& options) {
  std::string label;
  for (const auto& f : files) label += (label.empty() ? "" : "+") + f.name;
  return label + " [" + options.str() + "]";
}

// "file.cl:k" for line `line` (1-based) of assemble_source's text, or "" when it is the header or a #line directive.
std::string source_location(const std::vector<SourceFile>& files, size_t line) {
  size_t start = 2;  // line 1 is the header comment; each file starts with its #line directive
  for (const auto& file : files) {
    const size_t count = static_cast<size_t>(std::count(file.text.begin(), file.text.end(), '\n')) +
                         (file.text.empty() || file.text.back() != '\n' ? 1 : 0);
    if (line > start && line <= start + count) return file.name + ":" + std::to_string(line - start);
    start += count + 1;
  }
  return "";
}

// The first line of a build log that reports an error, e.g. "render.cl:12:5: error: ...". A compiler that ignores
// the #line directives (oclgrind's) names the assembled source instead ("input.cl:7:10: error: ..."): such a
// location is translated back to the file and line it came from.
std::string first_error_line(const std::string& log, const std::vector<SourceFile>& files) {
  std::istringstream lines(log);
  std::string line;
  while (std::getline(lines, line)) {
    if (line.find("error") == std::string::npos) continue;
    static const std::regex location(R"(^([^:\s]+):([0-9]+):)");
    std::smatch m;
    if (std::regex_search(line, m, location)) {
      const bool ours = std::any_of(files.begin(), files.end(), [&](const SourceFile& f) { return f.name == m[1].str(); });
      const std::string mapped = ours ? "" : source_location(files, std::stoul(m[2].str()));
      if (!mapped.empty()) return mapped + line.substr(m[0].length() - 1) + " (" + m[1].str() + ":" + m[2].str() + ")";
    }
    return line;
  }
  return log.empty() ? "the build log is empty" : log.substr(0, log.find('\n'));
}

}  // namespace

Program& ProgramCache::get(const std::vector<SourceFile>& files, const BuildOptions& options) {
  const std::string source = assemble_source(files, options);
  char hash[32];
  std::snprintf(hash, sizeof(hash), "%016llx", fnv1a_64(source));
  const std::string key = std::string(hash) + "|" + options.str();
  auto found = programs_.find(key);
  if (found != programs_.end()) return *found->second;

  const std::string label = label_of(files, options);
  cl_int status = CL_SUCCESS;
  ::cl::Program program(context_, source, false, &status);
  check(status, "clCreateProgramWithSource(" + label + ")");
  cl_int build_status = CL_SUCCESS;
  const std::string compiler_output =
      capture_stderr([&] { build_status = program.build({device_}, options.str().c_str()); });
  ++builds_;
  if (!compiler_output.empty() && log_) {
    log_(LogLevel::debug, "the compiler's output building " + label + ": " + compiler_output);
  }
  if (build_status != CL_SUCCESS) {
    cl_int log_status = CL_SUCCESS;
    const std::string log = program.getBuildInfo<CL_PROGRAM_BUILD_LOG>(device_, &log_status);
    if (build_status == CL_BUILD_PROGRAM_FAILURE || build_status == CL_INVALID_BUILD_OPTIONS) {
      throw Error("kernel build failed for " + label + " on '" + device_name_ + "': " + first_error_line(log, files) +
                      " (full log with --verbose)",
                  log, build_status);
    }
    check(build_status, "clBuildProgram(" + label + ")");
  }
  auto inserted = programs_.emplace(key, std::make_unique<Program>(std::move(program), label));
  return *inserted.first->second;
}

}  // namespace mipnerf::ocl

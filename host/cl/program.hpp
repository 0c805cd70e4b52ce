// Building OpenCL programs as specialisations (-D options), cached per (device, source hash, options).
#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "cl/opencl.hpp"
#include "core/log.hpp"

namespace mipnerf::ocl {

// The compile-time options of one specialisation. Defines are kept sorted, so the same set of
// options always produces the same string (and the same cache entry), whatever order they were set in.
class BuildOptions {
 public:
  BuildOptions& define(const std::string& name, const std::string& value = "1");
  BuildOptions& define(const std::string& name, long long value);
  BuildOptions& define(const std::string& name, int value) { return define(name, static_cast<long long>(value)); }
  // Written as an exact float literal (e.g. "0.00999999978f") so the kernel sees the host's float.
  BuildOptions& define_float(const std::string& name, float value);
  BuildOptions& flag(const std::string& compiler_flag);  // e.g. "-cl-denorms-are-zero"
  BuildOptions& merge(const BuildOptions& other);
  std::string str() const;  // "-DA=1 -DB=2 -cl-denorms-are-zero"
  bool empty() const { return defines_.empty() && flags_.empty(); }

 private:
  std::map<std::string, std::string> defines_;
  std::vector<std::string> flags_;
};

// One named piece of OpenCL C. Programs are made of several (e.g. "common.cl" then "render.cl"),
// each preceded by a #line directive so compiler messages name the original file and line.
struct SourceFile {
  std::string name;
  std::string text;
};

// Embedded kernels/<name> files, in order.
std::vector<SourceFile> embedded_sources(const std::vector<std::string>& names);

// A built program and its kernel objects, created once each.
class Program {
 public:
  Program(::cl::Program program, std::string label) : program_(std::move(program)), label_(std::move(label)) {}
  // Throws mipnerf::Error naming the kernel and the program when the kernel does not exist.
  ::cl::Kernel& kernel(const std::string& name);
  const std::string& label() const { return label_; }

 private:
  ::cl::Program program_;
  std::string label_;  // "render.cl [-DBACKGROUND=1]", used in error messages
  std::map<std::string, ::cl::Kernel> kernels_;
};

// The text actually compiled: a first line recording the options (so any on-disk cache keyed by the
// source, like PoCL's, also changes with them), then each file after its #line directive.
std::string assemble_source(const std::vector<SourceFile>& files, const BuildOptions& options);

// In-process cache of built programs, keyed by device, a hash of the assembled source, and options.
class ProgramCache {
 public:
  ProgramCache(::cl::Context context, ::cl::Device device, std::string device_name)
      : context_(std::move(context)), device_(std::move(device)), device_name_(std::move(device_name)) {}

  // Builds (or returns the cached) program. A compile error throws mipnerf::Error whose message holds
  // the first error line of the log ("render.cl:12:5: error: ...") and whose details() hold the full log.
  Program& get(const std::vector<SourceFile>& files, const BuildOptions& options);
  size_t size() const { return programs_.size(); }
  size_t builds() const { return builds_; }  // how many get() calls actually compiled
  // Where what the compiler writes to stderr during a build goes (debug level; cl/compiler_output.hpp).
  void set_log(LogFn log) { log_ = std::move(log); }

 private:
  LogFn log_;
  ::cl::Context context_;
  ::cl::Device device_;
  std::string device_name_;
  std::map<std::string, std::unique_ptr<Program>> programs_;
  size_t builds_ = 0;
};

// 64-bit FNV-1a, used for the cache key (not for security).
unsigned long long fnv1a_64(const std::string& text);

}  // namespace mipnerf::ocl

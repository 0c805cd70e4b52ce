// Kernel building: specialisations by compile-time options, the program cache, readable build errors.
#include <doctest/doctest.h>

#include <unistd.h>

#include <chrono>
#include <cstdio>

#include "cl/buffer.hpp"
#include "core/error.hpp"
#include "cl/launch.hpp"
#include "support/test_context.hpp"

using namespace mipnerf;

namespace {

// Runs util.cl's scale_f32 built with the given options over `x`; returns y.
std::vector<float> run_scale(ocl::Context& ctx, const ocl::BuildOptions& options, const std::vector<float>& x) {
  auto& kernel = ctx.program({"common.cl", "util.cl"}, options).kernel("scale_f32");
  ocl::DeviceArray<float> in(ctx, x.size(), "x"), out(ctx, x.size(), "y");
  in.upload(ctx, x);
  set_args(kernel, "scale_f32", in, out, static_cast<cl_uint>(x.size()));
  ocl::launch_1d(ctx, kernel, x.size(), "scale_f32");
  return out.download(ctx);
}

}  // namespace

TEST_CASE("program: two specialisations of one kernel give different results") {
  auto& ctx = test::test_context();
  // 1000 is not a multiple of the work-group size: the padded launch must leave y[1000..] alone
  // and compute every y[i < 1000].
  std::vector<float> x(1000);
  for (size_t i = 0; i < x.size(); ++i) x[i] = static_cast<float>(i) - 500.0f;
  const auto y_default = run_scale(ctx, {}, x);
  const auto y_times3 = run_scale(ctx, ocl::BuildOptions().define_float("SCALE_FACTOR", 3.0f), x);
  for (size_t i = 0; i < x.size(); ++i) {
    CHECK(y_default[i] == x[i]);
    CHECK(y_times3[i] == 3.0f * x[i]);
  }
}

TEST_CASE("program: the cache keys on options, not on the order they were given") {
  auto& ctx = test::test_context();
  const auto a = ocl::BuildOptions().define("ALPHA", 1).define("BETA", 2);
  const auto b = ocl::BuildOptions().define("BETA", 2).define("ALPHA", 1);
  CHECK(a.str() == b.str());
  auto& p1 = ctx.program({"common.cl", "util.cl"}, a);
  const size_t builds = ctx.program_cache().builds();
  auto& p2 = ctx.program({"common.cl", "util.cl"}, b);
  CHECK(&p1 == &p2);
  CHECK(ctx.program_cache().builds() == builds);
  auto& p3 = ctx.program({"common.cl", "util.cl"}, ocl::BuildOptions().define("ALPHA", 1).define("BETA", 3));
  CHECK(&p3 != &p1);
  CHECK(ctx.program_cache().builds() == builds + 1);
}

TEST_CASE("program: options are recorded in the compiled source, so on-disk caches key on them too") {
  const auto options = ocl::BuildOptions().define("RAY_SHAPE", 2).define_float("PAD", 0.01f);
  const std::string text = ocl::assemble_source({{"a.cl", "kernel void k() {}"}}, options);
  CHECK(text.find(options.str()) != std::string::npos);
  CHECK(text.find("#line 1 \"a.cl\"") != std::string::npos);
  CHECK(ocl::fnv1a_64(text) != ocl::fnv1a_64(ocl::assemble_source({{"a.cl", "kernel void k() {}"}}, {})));
  CHECK(options.str() == "-DPAD=0.00999999978f -DRAY_SHAPE=2");
  CHECK(ocl::BuildOptions().define_float("X", 2.0f).str() == "-DX=2.0f");
}

TEST_CASE("program: a compile error names the file and line") {
  auto& ctx = test::test_context();
  const std::vector<ocl::SourceFile> files = {
      {"good.cl", "inline float twice(float x) { return 2.0f * x; }\n"},
      {"broken.cl", "__kernel void k(__global float* y) {\n  y[0] = twice(1.0f);\n  y[1] = undefined_name;\n}\n"}};
  try {
    ctx.program_from_sources(files);
    FAIL("the broken source must not build");
  } catch (const Error& e) {
    const std::string message = e.what();
    INFO(message);
    CHECK(message.find("broken.cl:3") != std::string::npos);
    CHECK(message.find("undefined_name") != std::string::npos);
    CHECK(message.find('\n') == std::string::npos);
    CHECK(e.details().find("undefined_name") != std::string::npos);
    CHECK(e.status() == CL_BUILD_PROGRAM_FAILURE);
  }
}

TEST_CASE("program: an unknown kernel or file is a clear error") {
  auto& ctx = test::test_context();
  auto& program = ctx.program({"common.cl", "util.cl"});
  CHECK_THROWS_WITH_AS(program.kernel("no_such_kernel"), doctest::Contains("no_such_kernel"), Error);
  CHECK_THROWS_WITH_AS(ctx.program({"no_such_file.cl"}), doctest::Contains("no_such_file.cl"), Error);
}

TEST_CASE("buffers: sizes are checked and copies round-trip") {
  auto& ctx = test::test_context();
  ocl::DeviceArray<float> a(ctx, 10, "a [10]");
  std::vector<float> values(10);
  for (size_t i = 0; i < values.size(); ++i) values[i] = 0.5f * static_cast<float>(i);
  a.upload(ctx, values);
  CHECK(a.download(ctx) == values);
  a.fill(ctx, 7.0f);
  CHECK(a.download(ctx) == std::vector<float>(10, 7.0f));
  std::vector<float> eleven(11);
  CHECK_THROWS_WITH_AS(a.upload(ctx, eleven), doctest::Contains("a [10]"), Error);
  CHECK_THROWS_AS(a.require_size(11, "test"), Error);
  const size_t too_big = static_cast<size_t>(ctx.device_info().max_alloc_bytes / sizeof(float)) + 1;
  CHECK_THROWS_WITH_AS(ocl::DeviceArray<float>(ctx, too_big, "huge"),
                       doctest::Contains("lower batch_size or chunk_rays"), Error);
}

// PoCL compiles in-process with clang, which writes its summary ("1 warning generated.") to file descriptor 2, into the
// middle of train's and render's output. A kernel with a warning is built (its source made unique, so no runtime's
// cache has it) with fd 2 sent to a file here: nothing may arrive there, and on PoCL the compiler's line reaches the
// log instead (shown under --verbose).
TEST_CASE("program: what the compiler writes to stderr goes to the log, not to the tool's output") {
  ocl::Context ctx(test::test_context().device_info());
  std::vector<std::string> logged;
  ctx.set_log([&](LogLevel, const std::string& message) { logged.push_back(message); });
  const std::string unique = std::to_string(std::chrono::steady_clock::now().time_since_epoch().count()) + "_" +
                             std::to_string(::getpid());
  // An unused expression's result: a warning clang gives by default (an empty if body is not reported after our
  // #line; incompatible pointer types are an error on Intel's compiler).
  const ocl::SourceFile source{"warns.cl", "__kernel void warns_" + unique + "(__global float* x) { x[1]; x[0] = 1.0f; }\n"};
  std::FILE* caught = std::tmpfile();
  REQUIRE(caught != nullptr);
  std::fflush(stderr);
  const int saved = dup(2);
  dup2(fileno(caught), 2);
  std::string error;
  try {
    ctx.program_from_sources({source});
  } catch (const Error& e) {
    error = e.what();
  }
  std::fflush(stderr);
  dup2(saved, 2);
  close(saved);
  std::rewind(caught);
  std::string reached_stderr;
  char buffer[512];
  for (size_t n; (n = std::fread(buffer, 1, sizeof(buffer), caught)) > 0;) reached_stderr.append(buffer, n);
  std::fclose(caught);
  CHECK(error.empty());
  CHECK(reached_stderr.empty());
  if (ctx.device_info().platform_name == "Portable Computing Language") {
    const bool in_log = std::any_of(logged.begin(), logged.end(), [](const std::string& line) {
      return line.find("warning generated") != std::string::npos;
    });
    CHECK(in_log);  // the capture caught what PoCL's clang printed (without it, the line above fails instead)
  }
}

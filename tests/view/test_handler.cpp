// The viewer's request handler without sockets: the run folder's files and nothing outside it, the token, the request
// bounds, malformed render requests, and the run's state as the page reads it.
#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "io/temporary_folder.hpp"
#include "view/handler.hpp"
#include "view/run_state.hpp"

namespace fs = std::filesystem;
using namespace mipnerf;
using namespace mipnerf::view;

namespace {

void write_file(const fs::path& path, const std::string& text) {
  fs::create_directories(path.parent_path());
  std::ofstream(path, std::ios::binary) << text;
}

// A run folder (logs, config, a val image) inside a scratch folder that also holds a secret beside it.
struct RunFixture {
  io::TemporaryFolder scratch{fs::temp_directory_path(), "mipnerf-view-test-"};
  fs::path run = fs::path(scratch.path()) / "run";
  fs::path secret = fs::path(scratch.path()) / "secret.txt";
  RunFixture() {
    write_file(run / "config.json", R"({"steps": 10, "preset": "tiny"})");
    write_file(run / "train_log.csv", "step,wall_seconds,loss,psnr\n2,0.5,0.3,9.5\n4,1.0,0.2,11.25\n6,1.5,0.1");
    write_file(run / "val_log.csv", "step,train_seconds,val_psnr\n4,1.0,10.5\n");
    write_file(run / "val" / "000_scale0.png", "PNGDATA");
    write_file(run / "eval" / "images" / "r_0.png", "R");
    write_file(run / "eval" / "images" / "r_0_gt.png", "G");
    write_file(run / "eval" / "images" / "r_0_error.png", "E");
    write_file(secret, "top secret");
  }
};

// A renderer that records what it was asked and answers a 1-byte "image".
struct FakeBackend : RenderBackend {
  RenderRequest last;
  int calls = 0;
  RenderReply render(const RenderRequest& request) override {
    last = request;
    ++calls;
    RenderReply reply;
    reply.png = "P";
    reply.width = 8;
    reply.height = 6;
    return reply;
  }
  data::CameraPathDefaults camera_defaults() override { return {}; }
  StartCameras start_cameras() override { return {}; }
  ViewerStatus status() override {
    ViewerStatus s;
    s.device = "fake";
    s.step = 4;
    return s;
  }
  RenderProgress render_progress() override {
    RenderProgress p;
    p.rendering = true;
    p.generation = 3;
    p.divisor = 2;
    p.done_rays = 12;
    p.total_rays = 48;
    p.seconds = 0.5;
    return p;
  }
  // Paths: records the request; a second start while "rendering" is busy, as the real renderer's.
  PathRequest last_path;
  bool path_rendering = false;
  bool path_cancelled = false;
  PathReply start_path(const PathRequest& request) override {
    PathReply reply;
    if (path_rendering) {
      reply.status = PathReply::Status::busy;
      reply.message = "a path is rendering already";
      return reply;
    }
    last_path = request;
    path_rendering = true;
    return reply;
  }
  PathStatus path_status() override {
    PathStatus status;
    if (path_rendering) {
      status.state = PathStatus::State::rendering;
      status.frames = 12;
    }
    return status;
  }
  void cancel_path() override { path_cancelled = true; }
};

HandlerOptions options_for(const RunFixture& f) {
  HandlerOptions options;
  options.run_folder = f.run.string();
  options.bound = {"127.0.0.1", 8000};
  return options;
}

// A request as the viewer's own page sends it to a viewer on 127.0.0.1:8000: its Host, and for a POST the page's
// origin and a JSON body.
Request from_page(const std::string& method, const std::string& target, const std::string& body) {
  Request r{method, target, body, "127.0.0.1:8000", "", "", ""};
  if (method != "GET" && method != "HEAD") {
    r.origin = "http://127.0.0.1:8000";
    r.content_type = "application/json";
    r.sec_fetch_site = "same-origin";
  }
  return r;
}
Response get(const Handler& h, const std::string& target) { return h.handle(from_page("GET", target, "")); }
Response post(const Handler& h, const std::string& target, const std::string& body) {
  return h.handle(from_page("POST", target, body));
}

const char* kCamera = R"({"frames": [{"transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,4],[0,0,0,1]],
  "fl_x": 10, "fl_y": 10, "cx": 4, "cy": 3, "w": 8, "h": 6}]})";

std::string render_body(const std::string& camera, int divisor, int generation) {
  return std::string(R"({"camera": )") + camera + R"(, "divisor": )" + std::to_string(divisor) +
         R"(, "generation": )" + std::to_string(generation) + "}";
}

}  // namespace

TEST_CASE("handler: serves the page and the run folder's files") {
  RunFixture f;
  const Handler h(options_for(f), nullptr);
  const Response page = get(h, "/");
  CHECK(page.status == 200);
  CHECK(page.content_type.find("text/html") == 0);
  CHECK(page.body.find("mipnerf-cl view") != std::string::npos);
  const Response image = get(h, "/run/val/000_scale0.png");
  CHECK(image.status == 200);
  CHECK(image.content_type == "image/png");
  CHECK(image.body == "PNGDATA");
  CHECK(get(h, "/run/val/%30%30%30_scale0.png").body == "PNGDATA");  // percent-encoded name
  CHECK(get(h, "/run/val/missing.png").status == 404);
  CHECK(get(h, "/run/val").status == 404);  // a folder is not a file
  CHECK(get(h, "/nowhere").status == 404);
}

TEST_CASE("handler: refuses every path out of the run folder") {
  RunFixture f;
  const Handler h(options_for(f), nullptr);
  for (const char* target : {"/run/../secret.txt", "/run/val/../../secret.txt", "/run/%2e%2e/secret.txt",
                             "/run/%2E%2E%2Fsecret.txt", "/run/val/%2e%2e/%2e%2e/secret.txt", "/run//etc/passwd",
                             "/run/%2fetc%2fpasswd", "/run/..%5csecret.txt", "/run/val%00.png", "/run/%zz",
                             "/run/%", "/run/%4"}) {
    CAPTURE(target);
    const Response r = get(h, target);
    CHECK(r.status >= 400);
    CHECK(r.body.find("top secret") == std::string::npos);
  }
  const std::string absolute = "/run/" + f.secret.string();  // "/run//tmp/.../secret.txt"
  CHECK(get(h, absolute).status == 404);
}

TEST_CASE("handler: refuses a symlink that leads out of the run folder, serves one that stays inside") {
  RunFixture f;
  fs::create_symlink(f.secret, f.run / "link_out.txt");
  fs::create_directory_symlink(f.scratch.path(), f.run / "dir_out");
  fs::create_symlink(f.run / "val" / "000_scale0.png", f.run / "link_in.png");
  const Handler h(options_for(f), nullptr);
  CHECK(get(h, "/run/link_out.txt").status == 404);
  CHECK(get(h, "/run/dir_out/secret.txt").status == 404);
  const Response inside = get(h, "/run/link_in.png");
  CHECK(inside.status == 200);
  CHECK(inside.body == "PNGDATA");
  // resolve_inside on its own: the same answers.
  const std::string root = fs::canonical(f.run).string();
  CHECK(resolve_inside(root, "link_out.txt").empty());
  CHECK(resolve_inside(root, "../secret.txt").empty());
  CHECK(resolve_inside(root, f.secret.string()).empty());
  CHECK(resolve_inside(root, "val/000_scale0.png") == (fs::canonical(f.run) / "val" / "000_scale0.png").string());
}

TEST_CASE("handler: a folder whose name extends the run folder's is outside it") {
  RunFixture f;
  write_file(fs::path(f.scratch.path()) / "run2" / "x.txt", "sibling");
  fs::create_symlink(fs::path(f.scratch.path()) / "run2" / "x.txt", f.run / "sibling.txt");
  const Handler h(options_for(f), nullptr);
  CHECK(get(h, "/run/sibling.txt").status == 404);  // "/…/run2/x.txt" starts with "/…/run" as text, not as a path
}

TEST_CASE("handler: a token is required when one is set, and compared whole") {
  RunFixture f;
  HandlerOptions options = options_for(f);
  options.token = "0123456789abcdef";
  const Handler h(options, nullptr);
  CHECK(get(h, "/").status == 403);
  CHECK(get(h, "/api/run").status == 403);
  CHECK(get(h, "/run/val/000_scale0.png").status == 403);
  CHECK(get(h, "/?token=0123456789abcde").status == 403);
  CHECK(get(h, "/?token=0123456789abcdef0").status == 403);
  CHECK(get(h, "/?token=").status == 403);
  CHECK(get(h, "/?tokenx=0123456789abcdef").status == 403);
  CHECK(get(h, "/?token=0123456789abcdef").status == 200);
  CHECK(get(h, "/run/val/000_scale0.png?x=1&token=0123456789abcdef").body == "PNGDATA");
  CHECK(get(h, "/?token=%30123456789abcdef").status == 200);  // percent-encoded: the same token
  CHECK(same_secret("abc", "abc"));
  CHECK_FALSE(same_secret("abc", "abd"));
  CHECK_FALSE(same_secret("abc", "ab"));
  CHECK_FALSE(same_secret("", "a"));
}

TEST_CASE("handler: without a token, loopback serves everything") {
  RunFixture f;
  const Handler h(options_for(f), nullptr);
  CHECK(get(h, "/?token=anything").status == 200);
}

// DNS rebinding: a page on attacker.example rebinds its name to 127.0.0.1; the browser then sends the attacker's name
// as Host. Every request naming another host or port is refused before any route, file or render.
TEST_CASE("handler: a request whose Host is not the viewer's is refused, whatever it asks") {
  RunFixture f;
  FakeBackend backend;
  const Handler h(options_for(f), &backend);
  for (const std::string& host :
       {std::string("attacker.example:8000"), std::string("attacker.example"), std::string("127.0.0.1:8001"),
        std::string("127.0.0.1"), std::string("localhost:80"), std::string(""), std::string("127.0.0.1:8000x"),
        std::string("127.0.0.1:08000x"), std::string("[::1]"), std::string("::1:8000"), std::string("127.0.0.2:8000"),
        std::string("localhost.attacker.example:8000"), std::string("127.0.0.1:8000, attacker.example"),
        std::string("127.0.0.1:65536"), std::string("127.0.0.1:-8000")}) {
    CAPTURE(host);
    for (const char* target : {"/", "/api/run", "/run/val/000_scale0.png", "/api/cameras", "/api/path"}) {
      Request r = from_page("GET", target, "");
      r.host = host;
      const Response response = h.handle(r);
      CHECK(response.status == 403);
      CHECK(response.body.find("PNGDATA") == std::string::npos);
    }
    Request r = from_page("POST", "/api/render", render_body(kCamera, 1, 1));
    r.host = host;
    CHECK(h.handle(r).status == 403);
  }
  CHECK(backend.calls == 0);
  // The names of this machine's loopback, with the bound port, in any case.
  for (const char* host : {"127.0.0.1:8000", "localhost:8000", "LocalHost:8000", "[::1]:8000", " 127.0.0.1:8000"}) {
    CAPTURE(host);
    Request r = from_page("GET", "/run/val/000_scale0.png", "");
    r.host = host;
    CHECK(h.handle(r).body == "PNGDATA");
  }
}

TEST_CASE("handler: Host names the bound address, or on every address any name with the token") {
  RunFixture f;
  HandlerOptions options = options_for(f);
  options.bound = {"192.168.1.5", 8080};
  const Handler lan(options, nullptr);
  Request r = from_page("GET", "/api/run", "");
  for (const auto& host_status : std::vector<std::pair<std::string, int>>{
           {"192.168.1.5:8080", 200}, {"localhost:8080", 200}, {"192.168.1.6:8080", 403}, {"192.168.1.5:8000", 403}}) {
    CAPTURE(host_status.first);
    r.host = host_status.first;
    CHECK(lan.handle(r).status == host_status.second);
  }
  options.bound = {"::1", 8000};
  const Handler v6(options, nullptr);
  r.host = "[::1]:8000";
  CHECK(v6.handle(r).status == 200);
  // Bound to every address (--host 0.0.0.0), the machine's names are unknown: the token, always set there, guards.
  options.bound = {"0.0.0.0", 8000};
  options.token = "0123456789abcdef";
  const Handler everywhere(options, nullptr);
  r.host = "my-laptop.lan:8000";
  CHECK(everywhere.handle(r).status == 403);  // no token
  r.target = "/api/run?token=0123456789abcdef";
  CHECK(everywhere.handle(r).status == 200);
  r.host = "my-laptop.lan:9000";
  CHECK(everywhere.handle(r).status == 403);  // not its port
  // The port the server bound after the handler was made (--port 0).
  options.bound = {"127.0.0.1", 0};
  options.token.clear();
  Handler later(options, nullptr);
  r = from_page("GET", "/api/run", "");
  r.host = "127.0.0.1:43210";
  CHECK(later.handle(r).status == 403);  // not bound yet: nothing matches
  later.set_port(43210);
  CHECK(later.handle(r).status == 200);
}

// A page on another site can POST to the viewer (a form, or fetch with text/plain: no CORS preflight) though it cannot
// read the answer; such a POST would start renders that write into the run folder.
TEST_CASE("handler: a state-changing request from another origin, or not declared JSON, is refused") {
  RunFixture f;
  FakeBackend backend;
  const Handler h(options_for(f), &backend);
  const std::string path_body =
      std::string(R"({"keyframes": )") + kCamera + R"(, "frames": 12, "divisor": 2, "fps": 24})";
  for (const std::string& origin :
       {std::string("http://attacker.example"), std::string("http://attacker.example:8000"), std::string("null"),
        std::string("https://127.0.0.1:8000"), std::string("http://127.0.0.1:8001"), std::string("file://"),
        std::string("http://127.0.0.1:8000/x"), std::string("http://localhost.attacker.example:8000")}) {
    CAPTURE(origin);
    for (const std::string target : {"/api/path", "/api/path/cancel", "/api/render"}) {
      Request r = from_page("POST", target, target == "/api/render" ? render_body(kCamera, 1, 1) : path_body);
      r.origin = origin;
      r.sec_fetch_site = "";
      CHECK(h.handle(r).status == 403);
    }
  }
  for (const char* site : {"cross-site", "same-site"}) {
    Request r = from_page("POST", "/api/path", path_body);
    r.sec_fetch_site = site;
    r.origin = "";
    CHECK(h.handle(r).status == 403);
  }
  for (const std::string& type : {std::string("text/plain"), std::string("application/x-www-form-urlencoded"),
                                  std::string("multipart/form-data; boundary=x"), std::string(""),
                                  std::string("application/jsonx"), std::string("text/plain; application/json")}) {
    CAPTURE(type);
    Request r = from_page("POST", "/api/path", path_body);
    r.content_type = type;
    CHECK(h.handle(r).status == 415);
    r = from_page("POST", "/api/path/cancel", "{}");
    r.content_type = type;
    CHECK(h.handle(r).status == 415);
  }
  CHECK(backend.calls == 0);
  CHECK_FALSE(backend.path_rendering);
  CHECK_FALSE(backend.path_cancelled);
  // The page's own requests, and a client that sends no Origin (curl): accepted, in any JSON spelling.
  Request own = from_page("POST", "/api/path", path_body);
  own.content_type = "Application/JSON; charset=utf-8";
  CHECK(h.handle(own).status == 202);
  Request curl = from_page("POST", "/api/render", render_body(kCamera, 1, 1));
  curl.origin = curl.sec_fetch_site = "";
  CHECK(h.handle(curl).status == 200);
  // A GET from another origin changes nothing and its answer is not the other page's to read: served.
  Request image = from_page("GET", "/run/val/000_scale0.png", "");
  image.origin = "http://attacker.example";
  CHECK(h.handle(image).body == "PNGDATA");
}

TEST_CASE("handler: every response forbids framing, type sniffing and the Referer") {
  RunFixture f;
  const Handler h(options_for(f), nullptr);
  for (const Response& r : {get(h, "/"), get(h, "/nowhere"), post(h, "/api/path", "{}")}) {
    auto has = [&r](const std::string& name, const std::string& value) {
      return std::find(r.headers.begin(), r.headers.end(), std::make_pair(name, value)) != r.headers.end();
    };
    CHECK(has("X-Frame-Options", "DENY"));
    CHECK(has("Content-Security-Policy", "frame-ancestors 'none'"));
    CHECK(has("X-Content-Type-Options", "nosniff"));
    CHECK(has("Referrer-Policy", "no-referrer"));
  }
}

TEST_CASE("handler: bounds the request size") {
  RunFixture f;
  FakeBackend backend;
  const Handler h(options_for(f), &backend);
  const std::string huge(h.options().max_body_bytes + 1, ' ');
  CHECK(post(h, "/api/render", huge).status == 413);
  CHECK(get(h, "/" + std::string(h.options().max_target_bytes, 'a')).status == 414);
  CHECK(backend.calls == 0);
}

TEST_CASE("handler: malformed render requests are answered 400, never passed on") {
  RunFixture f;
  FakeBackend backend;
  const Handler h(options_for(f), &backend);
  for (const std::string& body :
       {std::string(""), std::string("{"), std::string("[]"), std::string("null"), std::string("{\"camera\": 1}"),
        render_body(kCamera, 0, 1), render_body(kCamera, 65, 1), render_body(kCamera, -8, 1),
        render_body(kCamera, 8, -1), render_body("[1, 2]", 8, 1), std::string(R"({"camera": {}, "divisor": 2.5, "generation": 1})"),
        std::string(R"({"camera": {}, "divisor": "8", "generation": 1})"),
        std::string(R"({"camera": {}, "divisor": 8, "generation": 1, "output": "normals"})"),
        std::string(R"({"camera": {}, "divisor": 8, "generation": 1, "output": 3})"),
        std::string("{\"camera\": {\"frames\": [}")}) {
    CAPTURE(body);
    CHECK(post(h, "/api/render", body).status == 400);
  }
  CHECK(backend.calls == 0);
  CHECK(get(h, "/api/render").status == 405);
  CHECK(post(h, "/", "").status == 405);
}

TEST_CASE("handler: a well-formed render request reaches the renderer with its camera, size and counter") {
  RunFixture f;
  FakeBackend backend;
  const Handler h(options_for(f), &backend);
  const Response r = post(h, "/api/render", render_body(kCamera, 4, 7));
  REQUIRE(r.status == 200);
  CHECK(r.content_type == "image/png");
  CHECK(r.body == "P");
  CHECK(backend.last.divisor == 4);
  CHECK(backend.last.generation == 7);
  CHECK(backend.last.output == RenderOutput::rgb);
  // The camera as the page sent it (the divisor is the renderer's to apply).
  const Camera& camera = backend.last.camera;
  CHECK(camera.width_px == 8);
  CHECK(camera.height_px == 6);
  CHECK(camera.focal_x_px == 10.0);
  CHECK(camera.center_y_px == 3.0);
  CHECK(camera.camera_to_world[11] == 4.0);
  CHECK(camera.near == 2.0);  // the renderer's defaults (Blender's 2..6 here) where the page gives none
  CHECK(camera.far == 6.0);
  bool size_header = false;
  for (const auto& [name, value] : r.headers) size_header |= name == "X-Render-Size" && value == "8x6";
  CHECK(size_header);
}

TEST_CASE("handler: a camera the camera path reader refuses is answered 400 with its reason, never passed on") {
  RunFixture f;
  FakeBackend backend;
  const Handler h(options_for(f), &backend);
  const std::string frame = R"({"transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,4],[0,0,0,1]], "fl_x": 10, "w": 8, "h": 6})";
  const std::string negative_focal = R"({"transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,4],[0,0,0,1]], "fl_x": -10, "w": 8, "h": 6})";
  const Response none = post(h, "/api/render", render_body("{}", 1, 1));
  CHECK(none.status == 400);
  const Response two = post(h, "/api/render", render_body(R"({"frames": [)" + frame + "," + frame + "]}", 1, 1));
  CHECK(two.status == 400);
  CHECK(two.body.find("exactly one frame") != std::string::npos);
  const Response bad = post(h, "/api/render", render_body(R"({"frames": [)" + negative_focal + "]}", 1, 1));
  CHECK(bad.status == 400);
  CHECK(bad.body.find("the page's camera") != std::string::npos);
  CHECK(post(h, "/api/render", render_body(R"({"frames": [)" + frame + "]}", 1, 1)).status == 200);
  CHECK(backend.calls == 1);
  const Response path = post(h, "/api/path", R"({"keyframes": {"frames": [)" + negative_focal + R"(]}, "frames": 4, "divisor": 1})");
  CHECK(path.status == 400);
  CHECK(path.body.find("the viewer's recorded path") != std::string::npos);
  CHECK_FALSE(backend.path_rendering);
}

TEST_CASE("handler: the renderer's state goes out as the API's JSON") {
  RunFixture f;
  struct Described : FakeBackend {
    StartCameras start_cameras() override {
      StartCameras c;
      Camera camera;
      camera.width_px = 8;
      camera.height_px = 6;
      c.train = {camera, camera};
      c.orbit.radius = 3.5;
      c.orbit.frame = camera;
      c.start = StartCameras::View::train;
      c.why = "forward";
      return c;
    }
  } backend;
  const Handler h(options_for(f), &backend);
  const auto cameras = nlohmann::json::parse(get(h, "/api/cameras").body);
  CHECK(cameras["train"].size() == 2);
  CHECK(cameras["train"][1]["w"] == 8);
  CHECK(cameras["spiral"] == nlohmann::json::array());
  CHECK(cameras["start"] == nlohmann::json{{"view", "train"}, {"index", 0}, {"why", "forward"}});
  CHECK(cameras["orbit"]["radius"] == 3.5);
  CHECK(cameras["orbit"]["up"] == nlohmann::json{0.0, 0.0, 1.0});
  CHECK(cameras["orbit"]["frame"]["h"] == 6);
  const auto run = nlohmann::json::parse(get(h, "/api/run").body);
  CHECK(run["viewer"] == nlohmann::json{{"device", "fake"}, {"step", 4}, {"checkpoint", ""}, {"chunk_rays", 0},
                                        {"warm_up_seconds", 0.0}});
  const auto idle = nlohmann::json::parse(get(h, "/api/path").body);
  CHECK(idle == nlohmann::json{{"state", "idle"}, {"frames_done", 0}, {"frames", 0}, {"seconds", 0.0},
                               {"eta_seconds", 0.0}, {"folder", ""}, {"video", ""}, {"first_frame", ""},
                               {"message", ""}});
}

TEST_CASE("handler: the renderer's refusals become HTTP statuses") {
  RunFixture f;
  struct Refusing : FakeBackend {
    RenderReply::Status status;
    RenderReply render(const RenderRequest&) override {
      RenderReply reply;
      reply.status = status;
      reply.message = "the page's camera: frames[0]: focal lengths must be positive and finite";
      return reply;
    }
  } backend;
  const Handler h(options_for(f), &backend);
  const std::pair<RenderReply::Status, int> cases[] = {{RenderReply::Status::superseded, 409},
                                                       {RenderReply::Status::busy, 503},
                                                       {RenderReply::Status::bad_request, 400},
                                                       {RenderReply::Status::failed, 500}};
  for (const auto& [status, http] : cases) {
    backend.status = status;
    CHECK(post(h, "/api/render", render_body(kCamera, 1, 1)).status == http);
  }
  CHECK(post(h, "/api/render", render_body(kCamera, 1, 1)).body.find("focal lengths") != std::string::npos);
}

TEST_CASE("handler: the run's state: config, logs as numbers (a row being written left out), images, renderer") {
  RunFixture f;
  FakeBackend backend;
  const Handler h(options_for(f), &backend);
  const Response r = get(h, "/api/run");
  REQUIRE(r.status == 200);
  const auto state = nlohmann::json::parse(r.body);
  CHECK(state["config"]["steps"] == 10);
  CHECK(state["train_log"]["columns"] == nlohmann::json({"step", "wall_seconds", "loss", "psnr"}));
  REQUIRE(state["train_log"]["rows"].size() == 2);  // "6,1.5,0.1" has no newline yet and a cell too few
  CHECK(state["train_log"]["rows"][1][3] == 11.25);
  CHECK(state["val_log"]["rows"][0][2] == 10.5);
  CHECK(state["viewer"]["device"] == "fake");
  REQUIRE(state["images"].size() == 2);
  nlohmann::json eval_image;
  for (const auto& im : state["images"]) {
    if (im["folder"] == "eval/images") eval_image = im;
  }
  CHECK(eval_image["render"] == "eval/images/r_0.png");
  CHECK(eval_image["gt"] == "eval/images/r_0_gt.png");
  CHECK(eval_image["error"] == "eval/images/r_0_error.png");
}

TEST_CASE("handler: a long log is thinned to the row limit, keeping its last row") {
  RunFixture f;
  std::string csv = "step,psnr\n";
  for (int i = 1; i <= 1000; ++i) csv += std::to_string(i) + "," + std::to_string(i * 0.01) + "\n";
  write_file(f.run / "long.csv", csv);
  const auto log = read_csv_log((f.run / "long.csv").string(), 100);
  CHECK(log["rows"].size() <= 101);
  CHECK(log["rows"].size() >= 100);
  CHECK(log["rows"].back()[0] == 1000);
  CHECK(read_csv_log((f.run / "none.csv").string()).is_null());
}

TEST_CASE("handler: percent-decoding and query values") {
  std::string out;
  CHECK(percent_decode("a%20b%2F", out));
  CHECK(out == "a b/");
  CHECK_FALSE(percent_decode("%", out));
  CHECK_FALSE(percent_decode("%2", out));
  CHECK_FALSE(percent_decode("%g0", out));
  CHECK_FALSE(percent_decode("a%00b", out));
  CHECK(query_value("a=1&token=x%41&b=2", "token") == "xA");
  CHECK(query_value("tokens=1", "token").empty());
  CHECK(query_value("", "token").empty());
}

TEST_CASE("handler: before the run's first checkpoint, renders wait (503), and the renderer set later serves them") {
  RunFixture f;
  Handler h(options_for(f), nullptr);
  CHECK(get(h, "/api/cameras").status == 503);
  CHECK(post(h, "/api/render", render_body(kCamera, 8, 1)).status == 503);
  CHECK(get(h, "/api/run").status == 200);  // the logs are shown meanwhile
  FakeBackend backend;
  h.set_backend(&backend);
  CHECK(get(h, "/api/cameras").status == 200);
  CHECK(post(h, "/api/render", render_body(kCamera, 8, 2)).status == 200);
  CHECK(backend.calls == 1);
}

TEST_CASE("handler: a run folder made after the viewer started is served once it exists") {
  io::TemporaryFolder scratch{fs::temp_directory_path(), "mipnerf-view-test-"};
  HandlerOptions options;
  options.run_folder = (fs::path(scratch.path()) / "later").string();
  options.bound = {"127.0.0.1", 8000};
  const Handler h(options, nullptr);
  CHECK(get(h, "/run/val/a.png").status == 404);
  CHECK(get(h, "/api/run").status == 200);
  write_file(fs::path(options.run_folder) / "val" / "a.png", "A");
  CHECK(get(h, "/run/val/a.png").body == "A");
}

TEST_CASE("handler: a recorded path starts once, reports its progress, and can be cancelled") {
  RunFixture f;
  FakeBackend backend;
  const Handler h(options_for(f), &backend);
  const std::string body =
      std::string(R"({"keyframes": )") + kCamera + R"(, "frames": 12, "divisor": 2, "fps": 24})";
  CHECK(get(h, "/api/path").body.find("idle") != std::string::npos);
  const Response started = post(h, "/api/path", body);
  CHECK(started.status == 202);
  CHECK(started.body.find("rendering") != std::string::npos);
  CHECK(backend.last_path.frames == 12);
  CHECK(backend.last_path.divisor == 2);
  CHECK(backend.last_path.fps == 24.0);
  REQUIRE(backend.last_path.keyframes.size() == 1);
  CHECK(backend.last_path.keyframes.front().width_px == 8);
  CHECK(post(h, "/api/path", body).status == 409);  // one path at a time
  CHECK(get(h, "/api/path").body.find("rendering") != std::string::npos);
  CHECK(post(h, "/api/path/cancel", "").status == 200);
  CHECK(backend.path_cancelled);
  CHECK(h.handle(from_page("PUT", "/api/path", "")).status == 405);
  CHECK(h.handle(from_page("GET", "/api/path/cancel", "")).status == 405);
}

TEST_CASE("handler: a malformed path request is refused before the renderer sees it") {
  RunFixture f;
  FakeBackend backend;
  const Handler h(options_for(f), &backend);
  const std::string keys = std::string(R"("keyframes": )") + kCamera;
  for (const std::string& body :
       {std::string("not json"), std::string("[]"), std::string(R"({"frames": 12, "divisor": 1})"),
        "{" + keys + R"(, "frames": 0, "divisor": 1})", "{" + keys + R"(, "frames": 3601, "divisor": 1})",
        "{" + keys + R"(, "frames": 12, "divisor": 0})", "{" + keys + R"(, "frames": 1.5, "divisor": 1})",
        "{" + keys + R"(, "frames": 12, "divisor": 1, "fps": 0})",
        "{" + keys + R"(, "frames": 12, "divisor": 1, "fps": "fast"})",
        std::string(R"({"keyframes": [], "frames": 12, "divisor": 1})")}) {
    CAPTURE(body);
    CHECK(post(h, "/api/path", body).status == 400);
  }
  CHECK_FALSE(backend.path_rendering);
  const Handler without_model(options_for(f), nullptr);
  CHECK(get(without_model, "/api/path").status == 503);
}

TEST_CASE("handler: multiscale val views are listed one per scale, each with its ground truth and error image") {
  RunFixture f;
  for (int scale = 0; scale < 4; ++scale) {
    const std::string stem = "001_scale" + std::to_string(scale);
    write_file(f.run / "val" / (stem + ".png"), "R");
    write_file(f.run / "val" / (stem + "_gt.png"), "G");
    write_file(f.run / "val" / (stem + "_error.png"), "E");
  }
  const Handler h(options_for(f), nullptr);
  const auto state = nlohmann::json::parse(get(h, "/api/run").body);
  std::vector<std::string> names;
  for (const auto& im : state["images"]) {
    if (im["folder"] != "val" || im["name"].get<std::string>().rfind("001_", 0) != 0) continue;
    const std::string name = im["name"];
    names.push_back(name);
    CHECK(im["render"] == "val/" + name + ".png");
    CHECK(im["gt"] == "val/" + name + "_gt.png");
    CHECK(im["error"] == "val/" + name + "_error.png");
  }
  CHECK(names == std::vector<std::string>{"001_scale0", "001_scale1", "001_scale2", "001_scale3"});
}

TEST_CASE("handler: the render under way reports its progress, read-only") {
  RunFixture f;
  FakeBackend backend;
  const Handler h(options_for(f), &backend);
  const Response r = get(h, "/api/render/progress");
  CHECK(r.status == 200);
  CHECK(r.content_type == "application/json");
  CHECK(nlohmann::json::parse(r.body) == nlohmann::json{{"rendering", true}, {"generation", 3}, {"divisor", 2},
                                                        {"done_rays", 12}, {"total_rays", 48}, {"seconds", 0.5}});
  CHECK(post(h, "/api/render/progress", "{}").status == 405);
  const Handler without_model(options_for(f), nullptr);
  CHECK(get(without_model, "/api/render/progress").status == 503);
}

// sulcus-cli end to end. run: outputs with the documented keys and columns, deterministic
// steps.csv, and bad input exiting 2 with one line naming the file and the fault.
#include "sulcus/content/gltf_io.h"
#include "sulcus/content/primitives.h"
#include "sulcus/engine/mesh.h"
#include "sulcus/haptics/recording.h"

#include "cli_run.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <sys/wait.h>

using namespace sulcus;
namespace fs = std::filesystem;
using test::kCli;
using test::Outcome;
using test::run_cli;

namespace {

void write_text(const fs::path& p, const std::string& s) {
    std::ofstream f(p);
    f << s;
}

int count_lines(const std::string& s) {
    int n = 0;
    for (char c : s)
        if (c == '\n') ++n;
    return n;
}

class Cli : public ::testing::Test {
protected:
    fs::path dir;
    void SetUp() override {
        dir = fs::temp_directory_path() /
              ("sulcus_cli_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
        fs::remove_all(dir);
        fs::create_directories(dir);
        std::string err;
        ASSERT_TRUE(write_obj(make_box(Vec3(0.005)), (dir / "cube.obj").string(), &err)) << err;
        ASSERT_TRUE(write_obj(make_box(Vec3(0.05, 0.01, 0.05), Vec3(0, -0.01, 0)), (dir / "floor.obj").string(), &err));
        write_text(dir / "traj.csv",
                   "t,x,y,z,qw,qx,qy,qz\n0,0,0.006,0,1,0,0,0\n0.1,0,0.004,0,1,0,0,0\n0.2,0.003,0.004,0,1,0,0,0\n"
                   "0.3,0,0.008,0,1,0,0,0\n");
        write_scene("scene.json", "cube.obj", "floor.obj", "traj.csv");
    }
    void TearDown() override { fs::remove_all(dir); }

    void write_scene(const std::string& name, const std::string& tool, const std::string& obj,
                     const std::string& traj, const std::string& format = "sulcus.scene/1") {
        write_text(dir / name, "{\"format\": \"" + format + "\", \"objects\": [{\"name\": \"floor\", \"mesh\": \"" + obj +
                                   "\"}], \"tool\": {\"name\": \"cube\", \"mesh\": \"" + tool +
                                   "\"}, \"trajectory\": \"" + traj + "\", \"rate_hz\": 1000}");
    }

    // Runs a bad input and checks: exit 2, one line, naming `file` and containing `what`.
    void expect_bad(const std::string& scene, const std::string& file, const std::string& what) {
        const Outcome o = run_cli("run " + (dir / scene).string() + " --out " + (dir / "o").string(), dir);
        EXPECT_EQ(o.status, 2) << o.err;
        EXPECT_EQ(count_lines(o.err), 1) << o.err;
        EXPECT_NE(o.err.find(file), std::string::npos) << o.err;
        EXPECT_NE(o.err.find(what), std::string::npos) << o.err;
        EXPECT_FALSE(fs::exists(dir / "o" / "summary.json"));
    }
};

std::string strip_step_us(const std::string& csv) {
    // Removes the 22nd column (step_us) of every row.
    std::stringstream in(csv), out;
    std::string line;
    while (std::getline(in, line)) {
        std::stringstream ls(line);
        std::string cell;
        int col = 0;
        while (std::getline(ls, cell, ',')) {
            if (col != 21) out << cell << ',';
            ++col;
        }
        out << '\n';
    }
    return out.str();
}

// The servo command with each device: a missing vendor library or device is one line and exit
// 2; the Phantom backend on the test's fake libHD runs the loop and records the session.
TEST_F(Cli, ServoDevicesOpenOrSayWhyNot) {
    const std::string scene = (dir / "scene.json").string();
    Outcome o = run_cli("servo --device phantom --scene " + scene + " --seconds 0.2", dir);
    if (std::getenv("SULCUS_LIBHD") == nullptr) {
        EXPECT_EQ(o.status, 2);
        EXPECT_NE(o.err.find("libHD.so"), std::string::npos) << o.err;
        EXPECT_EQ(count_lines(o.err), 1) << o.err;
    }
    o = run_cli("servo --device spacemouse --scene " + scene + " --seconds 0.2", dir);
    if (o.status != 0) {  // no SpaceMouse attached (the usual case): one line saying so
        EXPECT_EQ(o.status, 2);
        EXPECT_NE(o.err.find("spacemouse"), std::string::npos) << o.err;
        EXPECT_EQ(count_lines(o.err), 1) << o.err;
    }
    EXPECT_EQ(run_cli("servo --device falcon --scene " + scene, dir).status, 2);

    const std::string fake = std::string(SULCUS_BINARY_DIR) + "/fake_hd/libHD.so";
    ASSERT_TRUE(fs::exists(fake));
    const std::string rec = (dir / "phantom.rec").string();
    const std::string cmd = "SULCUS_LIBHD=" + fake + " " + kCli + " servo --device phantom --scene " + scene +
                            " --seconds 0.3 --record " + rec + " >" + (dir / "out.txt").string() + " 2>&1";
    EXPECT_EQ(std::system(cmd.c_str()), 0);
    const RecordingRead r = read_recording(rec);
    ASSERT_TRUE(r.ok()) << r.error;
    EXPECT_GT(r.ticks.size(), 200u);
    EXPECT_EQ(r.metadata.device, "phantom");
    ASSERT_FALSE(r.events.empty());
    EXPECT_EQ(r.events.front().kind, "servo.begin");
}

TEST_F(Cli, DevicesListsOrSaysNone) {
    const Outcome o = run_cli("devices", dir);
    EXPECT_EQ(o.status, 0) << o.err;
    EXPECT_FALSE(o.out.empty());
    const Outcome j = run_cli("devices --json", dir);
    EXPECT_EQ(j.status, 0) << j.err;
    EXPECT_FALSE(nlohmann::json::parse(j.out, nullptr, false).is_discarded()) << j.out;
}

}  // namespace

TEST_F(Cli, RunWritesSummaryAndStepsWithTheDocumentedFields) {
    const Outcome o = run_cli("run " + (dir / "scene.json").string() + " --out " + (dir / "o").string() + " --plot", dir);
    ASSERT_EQ(o.status, 0) << o.err;
    EXPECT_EQ(count_lines(o.out), 1);
    std::ifstream sf(dir / "o" / "summary.json");
    const nlohmann::json j = nlohmann::json::parse(sf);
    for (const char* key : {"steps", "contact_steps", "max_penetration_m", "max_gap_in_contact_m", "max_force_N",
                            "max_torque_Nm", "max_force_step_N", "step_time_us", "nan_steps", "status_counts"})
        EXPECT_TRUE(j.contains(key)) << key;
    for (const char* key : {"median", "p99", "p999", "max"}) EXPECT_TRUE(j["step_time_us"].contains(key)) << key;
    EXPECT_EQ(j["steps"].get<long>(), 301);
    EXPECT_GT(j["contact_steps"].get<long>(), 100);
    EXPECT_NEAR(j["max_force_N"].get<double>(), 1.0, 1e-6);  // pressed 1 mm at 1000 N/m
    std::ifstream cf(dir / "o" / "steps.csv");
    std::string header;
    std::getline(cf, header);
    EXPECT_EQ(header,
              "t,hx,hy,hz,hqw,hqx,hqy,hqz,gx,gy,gz,gqw,gqx,gqy,gqz,fx,fy,fz,tx,ty,tz,step_us,penetration_m,contacts,status");
    EXPECT_TRUE(fs::exists(dir / "o" / "force.svg"));
    EXPECT_TRUE(fs::exists(dir / "o" / "step_time.svg"));
}

TEST_F(Cli, RunningTwiceGivesIdenticalStepsApartFromStepTime) {
    ASSERT_EQ(run_cli("run " + (dir / "scene.json").string() + " --out " + (dir / "a").string(), dir).status, 0);
    ASSERT_EQ(run_cli("run " + (dir / "scene.json").string() + " --out " + (dir / "b").string(), dir).status, 0);
    auto read = [](const fs::path& p) {
        std::ifstream f(p);
        std::stringstream s;
        s << f.rdbuf();
        return s.str();
    };
    const std::string a = read(dir / "a" / "steps.csv"), b = read(dir / "b" / "steps.csv");
    EXPECT_GT(a.size(), 1000u);
    EXPECT_EQ(strip_step_us(a), strip_step_us(b));
}

TEST_F(Cli, MissingSceneFile) { expect_bad("nope.json", "nope.json", ""); }

TEST_F(Cli, MalformedJson) {
    write_text(dir / "bad.json", "{\"format\": \"sulcus.scene/1\", \"objects\": [\n");
    expect_bad("bad.json", "bad.json", "line");
}

TEST_F(Cli, UnknownFormat) {
    write_scene("fmt.json", "cube.obj", "floor.obj", "traj.csv", "sulcus.scene/9");
    expect_bad("fmt.json", "fmt.json", "format");
}

TEST_F(Cli, MissingMesh) {
    write_scene("m.json", "cube.obj", "missing.obj", "traj.csv");
    expect_bad("m.json", "missing.obj", "");
}

TEST_F(Cli, OpenMesh) {
    TriMesh open = make_box(Vec3(0.05, 0.01, 0.05), Vec3(0, -0.01, 0));
    open.triangles.pop_back();
    std::string err;
    ASSERT_TRUE(write_obj(open, (dir / "open.obj").string(), &err));
    write_scene("o.json", "cube.obj", "open.obj", "traj.csv");
    expect_bad("o.json", "open.obj", "");
}

TEST_F(Cli, FlippedMesh) {
    TriMesh flipped = make_box(Vec3(0.05, 0.01, 0.05), Vec3(0, -0.01, 0));
    std::swap(flipped.triangles[3][1], flipped.triangles[3][2]);
    std::string err;
    ASSERT_TRUE(write_obj(flipped, (dir / "flip.obj").string(), &err));
    write_scene("f.json", "cube.obj", "flip.obj", "traj.csv");
    expect_bad("f.json", "flip.obj", "");
}

TEST_F(Cli, NanInTrajectory) {
    write_text(dir / "nan.csv", "t,x,y,z,qw,qx,qy,qz\n0,0,0.006,0,1,0,0,0\n0.1,nan,0.004,0,1,0,0,0\n");
    write_scene("n.json", "cube.obj", "floor.obj", "nan.csv");
    expect_bad("n.json", "nan.csv", "line 3");
}

TEST_F(Cli, TimeGoingBackwards) {
    write_text(dir / "back.csv", "t,x,y,z,qw,qx,qy,qz\n0,0,0.006,0,1,0,0,0\n0.2,0,0.006,0,1,0,0,0\n0.1,0,0.006,0,1,0,0,0\n");
    write_scene("b.json", "cube.obj", "floor.obj", "back.csv");
    expect_bad("b.json", "back.csv", "line 4");
}

TEST_F(Cli, FirstPosePenetrates) {
    write_text(dir / "pen.csv", "t,x,y,z,qw,qx,qy,qz\n0,0,0.001,0,1,0,0,0\n0.1,0,0.006,0,1,0,0,0\n");
    write_scene("p.json", "cube.obj", "floor.obj", "pen.csv");
    expect_bad("p.json", "pen.csv", "penetrates");
}

TEST_F(Cli, NonConvexTool) {
    const std::vector<Vec2> ell = {{0, 0}, {0.01, 0}, {0.01, 0.004}, {0.004, 0.004}, {0.004, 0.01}, {0, 0.01}};
    std::string err;
    ASSERT_TRUE(write_obj(make_extruded_polygon(ell, 0.02, 0.03), (dir / "ell.obj").string(), &err));
    write_scene("c.json", "ell.obj", "floor.obj", "traj.csv");
    expect_bad("c.json", "c.json", "not convex");
}

TEST_F(Cli, UsageErrors) {
    EXPECT_EQ(run_cli("", dir).status, 2);
    EXPECT_EQ(run_cli("frobnicate", dir).status, 2);
    EXPECT_EQ(run_cli("run", dir).status, 2);
    EXPECT_EQ(run_cli("run a.json --bogus", dir).status, 2);
    EXPECT_EQ(run_cli("help run", dir).status, 0);
}

// sulcus-cli content: teeth and probes as glTF, checks of charts, scenes and meshes, import.
TEST_F(Cli, ContentToothAndProbeWriteGltf) {
    const Outcome t = run_cli("content tooth 36 --out " + (dir / "t36.glb").string(), dir);
    ASSERT_EQ(t.status, 0) << t.err;
    const AssetLoad a = read_glb((dir / "t36.glb").string());
    ASSERT_TRUE(a.ok()) << a.error;
    ASSERT_EQ(a.asset.nodes.size(), 1u);
    EXPECT_EQ(a.asset.nodes[0].name, "tooth 36");
    EXPECT_EQ(a.asset.nodes[0].extras.value("fdi", 0), 36);
    EXPECT_EQ(a.asset.nodes[0].extras.value("universal", 0), 19);
    // The tooth's parts together are a closed solid the engine reads.
    const MeshLoad m = load_mesh((dir / "t36.glb").string());
    EXPECT_TRUE(m.ok()) << m.error;
    const size_t tris = m.mesh.triangles.size();
    EXPECT_GE(tris, 5000u);
    EXPECT_LE(tris, 20000u);

    const Outcome p = run_cli("content probe unc15 --out " + (dir / "p.glb").string(), dir);
    ASSERT_EQ(p.status, 0) << p.err;
    const AssetLoad b = read_glb((dir / "p.glb").string());
    ASSERT_TRUE(b.ok()) << b.error;
    EXPECT_EQ(b.asset.nodes.size(), 2u);  // body with markings, collision tip

    const Outcome bad = run_cli("content tooth 18 --out " + (dir / "t.glb").string(), dir);
    EXPECT_EQ(bad.status, 2);
    EXPECT_NE(bad.err.find("'18'"), std::string::npos) << bad.err;
    EXPECT_EQ(run_cli("content probe spoon --out x.glb", dir).status, 2);
    EXPECT_EQ(run_cli("content tooth 36", dir).status, 2);
    EXPECT_EQ(run_cli("help content", dir).status, 0);
}

TEST_F(Cli, ContentCheckReportsFaultsWithTheirPlace) {
    write_text(dir / "good.json", R"({"format": "sulcus.chart/1", "teeth": {"11": {"sites": {"B": {"pd_mm": 2}}}}})");
    const Outcome ok = run_cli("content check " + (dir / "good.json").string(), dir);
    EXPECT_EQ(ok.status, 0) << ok.err;
    EXPECT_NE(ok.out.find("chart ok"), std::string::npos);

    write_text(dir / "bad.json", R"({"format": "sulcus.chart/1", "teeth": {"11": {"sites": {"B": {"pd_mm": 99}}}}})");
    const Outcome bad = run_cli("content check " + (dir / "bad.json").string(), dir);
    EXPECT_EQ(bad.status, 1);
    EXPECT_EQ(count_lines(bad.err), 1) << bad.err;
    EXPECT_NE(bad.err.find("bad.json: /teeth/11/sites/B/pd_mm"), std::string::npos) << bad.err;

    const Outcome scene = run_cli("content check " + (dir / "scene.json").string(), dir);
    EXPECT_EQ(scene.status, 0) << scene.err;
    const Outcome mesh = run_cli("content check " + (dir / "cube.obj").string(), dir);
    EXPECT_EQ(mesh.status, 0) << mesh.err;
    EXPECT_NE(mesh.out.find("12 triangles"), std::string::npos) << mesh.out;

    write_text(dir / "open.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    const Outcome open = run_cli("content check " + (dir / "open.obj").string(), dir);
    EXPECT_EQ(open.status, 1);
    EXPECT_NE(open.err.find("open.obj"), std::string::npos) << open.err;
}

TEST_F(Cli, ContentCaseRejectsChartsItCannotBuild) {
    write_text(dir / "partial.json", R"({"format": "sulcus.chart/1", "teeth": {"11": {"sites": {"B": {"pd_mm": 2}}}}})");
    const Outcome o = run_cli("content case " + (dir / "partial.json").string() + " --out " + (dir / "c").string(), dir);
    EXPECT_EQ(o.status, 2);
    EXPECT_EQ(count_lines(o.err), 5) << o.err;  // five sites missing, one line each
    EXPECT_NE(o.err.find("partial.json: /teeth/11/sites/MB: missing"), std::string::npos) << o.err;
    EXPECT_FALSE(fs::exists(dir / "c"));
}

TEST_F(Cli, ContentImportScalesToMetres) {
    std::string err;
    ASSERT_TRUE(write_obj(make_box(Vec3(5.0)), (dir / "mm.obj").string(), &err)) << err;  // a 10 mm cube in mm
    const Outcome o = run_cli("content import " + (dir / "mm.obj").string() + " --unit mm --out " +
                                  (dir / "m.glb").string(), dir);
    ASSERT_EQ(o.status, 0) << o.err;
    const MeshLoad m = load_mesh((dir / "m.glb").string());
    ASSERT_TRUE(m.ok()) << m.error;
    EXPECT_NEAR(mesh_volume(m.mesh), 1e-6, 1e-12);
    EXPECT_EQ(run_cli("content import " + (dir / "mm.obj").string() + " --unit furlong --out x.glb", dir).status, 2);
}

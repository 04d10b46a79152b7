// The scene file reader: a valid scene loads with its defaults, and every kind of bad input gives
// one error line naming the file and the place in it. Trajectory rows and their interpolation.
#include "sulcus/engine/scene_file.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>

namespace sulcus {
namespace {

namespace fs = std::filesystem;

// A closed 1 cm cube with outward, counter-clockwise triangles.
constexpr const char* kCubeObj = R"(v 0 0 0
v 0.01 0 0
v 0.01 0.01 0
v 0 0.01 0
v 0 0 0.01
v 0.01 0 0.01
v 0.01 0.01 0.01
v 0 0.01 0.01
f 1 4 3
f 1 3 2
f 5 6 7
f 5 7 8
f 1 2 6
f 1 6 5
f 4 8 7
f 4 7 3
f 1 5 8
f 1 8 4
f 2 3 7
f 2 7 6
)";

constexpr const char* kTrajectory =
    "t,x,y,z,qw,qx,qy,qz\n"
    "0,0,0.02,0,1,0,0,0\n"
    "0.5,0,0.015,0,1,0,0,0\n"
    "1,0,0.01,0,1,0,0,0\n";

class SceneFileTest : public ::testing::Test {
protected:
    void SetUp() override {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        dir_ = fs::temp_directory_path() /
               ("sulcus_scene_" + std::string(info->name()) + "_" + std::to_string(::getpid()));
        fs::remove_all(dir_);
        fs::create_directories(dir_ / "meshes");
        write("meshes/cube.obj", kCubeObj);
        write("traj.csv", kTrajectory);
    }
    void TearDown() override { fs::remove_all(dir_); }

    std::string path(const std::string& name) const { return (dir_ / name).string(); }
    std::string write(const std::string& name, const std::string& text) const {
        std::ofstream(dir_ / name, std::ios::binary) << text;
        return path(name);
    }
    // A valid scene with `objects`, `extra` top-level text, and the tool and trajectory given.
    std::string scene(const std::string& objects, const std::string& extra = "",
                      const std::string& tool = R"("tool": {"name": "probe", "mesh": "meshes/cube.obj"},)",
                      const std::string& trajectory = R"("trajectory": "traj.csv")") const {
        return write("scene.json", "{\n  \"format\": \"sulcus.scene/1\",\n  \"objects\": [" + objects + "],\n  " +
                                       tool + "\n  " + extra + trajectory + "\n}\n");
    }

    fs::path dir_;
};

constexpr const char* kObject = R"({"name": "block", "mesh": "meshes/cube.obj"})";

// Every error line names the file, holds the place and is a single line.
::testing::AssertionResult has_error(const SceneLoad& load, const std::string& file, const std::string& place,
                                     const std::string& what = "") {
    for (const std::string& e : load.errors) {
        if (e.find('\n') != std::string::npos) return ::testing::AssertionFailure() << "multi-line error: " << e;
    }
    for (const std::string& e : load.errors) {
        if (e.find(file) != std::string::npos && e.find(place) != std::string::npos &&
            e.find(what) != std::string::npos)
            return ::testing::AssertionSuccess();
    }
    auto failure = ::testing::AssertionFailure() << "no error with '" << file << "', '" << place << "', '" << what
                                                 << "' among:";
    for (const std::string& e : load.errors) failure << "\n  " << e;
    return failure;
}

TEST_F(SceneFileTest, ValidSceneLoadsWithDefaults) {
    const std::string p = scene(kObject);
    const SceneLoad load = load_scene(p);
    ASSERT_TRUE(load.ok()) << load.errors.front();
    const SceneFile& s = load.scene;
    EXPECT_EQ(s.name, "scene");
    EXPECT_EQ(s.path, p);
    EXPECT_TRUE(s.warnings.empty());
    ASSERT_EQ(s.objects.size(), 1u);
    EXPECT_EQ(s.objects[0].name, "block");
    EXPECT_EQ(fs::path(s.objects[0].mesh_path), dir_ / "meshes" / "cube.obj");
    EXPECT_EQ(s.objects[0].pose.position, Vec3(0.0));
    EXPECT_EQ(s.objects[0].pose.orientation, Quat(1, 0, 0, 0));
    EXPECT_EQ(s.objects[0].mesh.triangles.size(), 12u);
    EXPECT_EQ(s.tool.name, "probe");
    EXPECT_EQ(s.tool.mesh.triangles.size(), 12u);
    const HapticSettings defaults;
    EXPECT_EQ(s.haptic.stiffness_N_per_m, defaults.stiffness_N_per_m);
    EXPECT_EQ(s.haptic.rotational_stiffness_Nm_per_rad, defaults.rotational_stiffness_Nm_per_rad);
    EXPECT_EQ(s.haptic.weight_translational, defaults.weight_translational);
    EXPECT_EQ(s.haptic.weight_rotational, defaults.weight_rotational);
    EXPECT_EQ(s.rate_hz, 1000.0);
    EXPECT_EQ(fs::path(s.trajectory_path), dir_ / "traj.csv");
    ASSERT_EQ(s.trajectory.size(), 3u);
    EXPECT_EQ(s.trajectory[1].t, 0.5);
    EXPECT_EQ(s.trajectory[1].pose.position, Vec3(0, 0.015, 0));
}

TEST_F(SceneFileTest, ExplicitValuesAreReadAndOrientationNormalised) {
    const std::string p = scene(
        R"({"name": "a", "mesh": "meshes/cube.obj", "position": [0.1, -2, 3e-3],
            "orientation": [0.7071068, 0, 0.7071068, 0]},
           {"name": "b", "mesh": "meshes/cube.obj"})",
        R"("haptic": {"stiffness_N_per_m": 500, "weight_rotational": 2e-4}, "rate_hz": 2000,)");
    const SceneLoad load = load_scene(p);
    ASSERT_TRUE(load.ok()) << load.errors.front();
    const SceneFile& s = load.scene;
    ASSERT_EQ(s.objects.size(), 2u);
    EXPECT_EQ(s.objects[0].pose.position, Vec3(0.1, -2, 3e-3));
    const Quat q = s.objects[0].pose.orientation;
    EXPECT_NEAR(glm::length(q), 1.0, 1e-15);
    EXPECT_NEAR(q.w, q.y, 1e-15);
    EXPECT_EQ(s.haptic.stiffness_N_per_m, 500.0);
    EXPECT_EQ(s.haptic.weight_rotational, 2e-4);
    EXPECT_EQ(s.haptic.weight_translational, HapticSettings{}.weight_translational);
    EXPECT_EQ(s.rate_hz, 2000.0);
}

TEST_F(SceneFileTest, MissingSceneFile) {
    const SceneLoad load = load_scene(path("nowhere.json"));
    EXPECT_FALSE(load.ok());
    EXPECT_TRUE(has_error(load, "nowhere.json", "not found"));
}

TEST_F(SceneFileTest, MalformedJsonGivesLineAndColumn) {
    const std::string p = write("scene.json", "{\n  \"format\": \"sulcus.scene/1\",\n  \"objects\": [ , ]\n}\n");
    const SceneLoad load = load_scene(p);
    ASSERT_EQ(load.errors.size(), 1u);
    EXPECT_TRUE(has_error(load, "scene.json", "line 3, column 16"));
}

TEST_F(SceneFileTest, TruncatedJsonPointsAtTheEnd) {
    const std::string p = write("scene.json", "{\n  \"format\": \"sulcus.scene/1\",\n  \"obj");
    const SceneLoad load = load_scene(p);
    EXPECT_TRUE(has_error(load, "scene.json", "line 3, column 7"));
}

TEST_F(SceneFileTest, UnknownFormat) {
    const std::string p = write("scene.json", R"({"format": "sulcus.scene/2", "objects": []})");
    const SceneLoad load = load_scene(p);
    EXPECT_TRUE(has_error(load, "scene.json", "/format", "unknown format 'sulcus.scene/2' (expected sulcus.scene/1)"));
}

TEST_F(SceneFileTest, TopLevelMustBeAnObject) {
    const SceneLoad load = load_scene(write("scene.json", "[1, 2]"));
    EXPECT_TRUE(has_error(load, "scene.json", "top level"));
}

TEST_F(SceneFileTest, EmptyObjects) {
    const SceneLoad load = load_scene(scene(""));
    EXPECT_TRUE(has_error(load, "scene.json", "/objects", "non-empty"));
}

TEST_F(SceneFileTest, MissingTool) {
    const SceneLoad load = load_scene(scene(kObject, "", ""));
    EXPECT_TRUE(has_error(load, "scene.json", "/tool", "missing"));
}

TEST_F(SceneFileTest, MissingObjectName) {
    const SceneLoad load = load_scene(scene(R"({"mesh": "meshes/cube.obj"})"));
    EXPECT_TRUE(has_error(load, "scene.json", "/objects/0/name", "missing"));
}

TEST_F(SceneFileTest, DuplicateObjectName) {
    const SceneLoad load = load_scene(scene(std::string(kObject) + "," + kObject));
    EXPECT_TRUE(has_error(load, "scene.json", "/objects/1/name", "duplicate"));
}

TEST_F(SceneFileTest, MissingMeshFile) {
    const SceneLoad load =
        load_scene(scene(std::string(kObject) + R"(, {"name": "gone", "mesh": "meshes/gone.obj"})"));
    EXPECT_TRUE(has_error(load, "scene.json", "/objects/1/mesh", "gone.obj"));
}

TEST_F(SceneFileTest, InvalidMeshErrorIsPassedOn) {
    // The cube without its last triangle is open: the mesh loader's own line names the mesh file.
    std::string open_cube = kCubeObj;
    open_cube.erase(open_cube.rfind("f 2 7 6"));
    write("meshes/open.obj", open_cube);
    const SceneLoad load =
        load_scene(scene(std::string(kObject) + R"(, {"name": "open", "mesh": "meshes/open.obj"})"));
    EXPECT_FALSE(load.ok());
    EXPECT_TRUE(has_error(load, "open.obj", ""));
}

TEST_F(SceneFileTest, NanPosition) {
    // JSON has no NaN literal: a writer that meant NaN leaves a string or null.
    const SceneLoad load = load_scene(
        scene(R"({"name": "a", "mesh": "meshes/cube.obj", "position": [0, "NaN", 0]})"));
    EXPECT_TRUE(has_error(load, "scene.json", "/objects/0/position/1", "finite"));
}

TEST_F(SceneFileTest, OverflowingNumberIsAParseErrorWithLineAndColumn) {
    const std::string p = write("scene.json", "{\n  \"format\": \"sulcus.scene/1\",\n  \"rate_hz\": 1e999\n}\n");
    const SceneLoad load = load_scene(p);
    ASSERT_EQ(load.errors.size(), 1u);
    EXPECT_TRUE(has_error(load, "scene.json", "line 3, column 18", "1e999"));
}

TEST_F(SceneFileTest, PositionOfWrongShapeOrType) {
    const SceneLoad load = load_scene(scene(
        R"({"name": "a", "mesh": "meshes/cube.obj", "position": [0, 1]},
           {"name": "b", "mesh": "meshes/cube.obj", "position": [0, null, "1"]})"));
    EXPECT_TRUE(has_error(load, "scene.json", "/objects/0/position", "3 numbers"));
    EXPECT_TRUE(has_error(load, "scene.json", "/objects/1/position/1"));
    EXPECT_TRUE(has_error(load, "scene.json", "/objects/1/position/2"));
}

TEST_F(SceneFileTest, NonUnitOrientation) {
    const SceneLoad load = load_scene(scene(
        R"({"name": "a", "mesh": "meshes/cube.obj", "orientation": [1, 0, 0, 0.01]},
           {"name": "b", "mesh": "meshes/cube.obj", "orientation": [0, 0, 0, 0]})"));
    EXPECT_TRUE(has_error(load, "scene.json", "/objects/0/orientation", "unit"));
    EXPECT_TRUE(has_error(load, "scene.json", "/objects/1/orientation", "length 0"));
}

TEST_F(SceneFileTest, UnknownKeysAreWarningsOnly) {
    const SceneLoad load = load_scene(
        scene(R"({"name": "a", "mesh": "meshes/cube.obj", "colour": "red"})",
              R"("haptic": {"damping": 1}, "lights": 2, "odd/key~\n": 0,)"));
    ASSERT_TRUE(load.ok()) << load.errors.front();
    const auto& w = load.scene.warnings;
    auto has = [&](const std::string& line) { return std::find(w.begin(), w.end(), line) != w.end(); };
    const std::string file = path("scene.json");
    EXPECT_TRUE(has(file + ": /objects/0/colour: unknown key (ignored)"));
    EXPECT_TRUE(has(file + ": /haptic/damping: unknown key (ignored)"));
    EXPECT_TRUE(has(file + ": /lights: unknown key (ignored)"));
    // JSON-pointer escapes, and the newline in the key does not break the line.
    EXPECT_TRUE(has(file + ": /odd~1key~0\\n: unknown key (ignored)"));
    for (const std::string& line : w) EXPECT_EQ(line.find('\n'), std::string::npos) << line;
}

TEST_F(SceneFileTest, BadHapticAndRate) {
    const SceneLoad load = load_scene(
        scene(kObject, R"("haptic": {"stiffness_N_per_m": -5, "weight_rotational": "big"}, "rate_hz": 1e6,)"));
    EXPECT_TRUE(has_error(load, "scene.json", "/haptic/stiffness_N_per_m", "positive"));
    EXPECT_TRUE(has_error(load, "scene.json", "/haptic/weight_rotational", "positive"));
    EXPECT_TRUE(has_error(load, "scene.json", "/rate_hz"));
}

TEST_F(SceneFileTest, CollectsAllErrors) {
    const SceneLoad load = load_scene(
        scene(R"({"name": "a", "mesh": "meshes/cube.obj", "position": [0, null, 0]})", R"("rate_hz": 0,)", "",
              R"("trajectory": "missing.csv")"));
    EXPECT_EQ(load.errors.size(), 4u);
    EXPECT_TRUE(has_error(load, "scene.json", "/objects/0/position/1"));
    EXPECT_TRUE(has_error(load, "scene.json", "/tool"));
    EXPECT_TRUE(has_error(load, "scene.json", "/rate_hz"));
    EXPECT_TRUE(has_error(load, "scene.json", "/trajectory", "missing.csv"));
}


constexpr const char* kMaterials = R"("materials": {
    "enamel": {"kind": "rigid", "friction_static": 0.2, "friction_kinetic": 0.1},
    "gum": {"kind": "compliant", "stiffness_N_per_m": 400, "friction_static": 0.5},
    "floor": {"kind": "compliant", "yield_curve_N_mm": [[0, 0], [0.25, 0.05], [0.5, 0.08]]}
  },)";

TEST_F(SceneFileTest, MaterialsAndRegionsAreRead) {
    const SceneLoad load = load_scene(scene(
        R"({"name": "tooth", "mesh": "meshes/cube.obj", "material": "enamel"},
           {"name": "gum", "mesh": "meshes/cube.obj", "material": "gum",
            "regions": [{"name": "floor MB", "material": "floor", "center": [0.005, 0.01, 0.005], "radius": 0.003,
                         "normal": [0, 2, 0], "min_cos": 0.5}]},
           {"name": "plain", "mesh": "meshes/cube.obj"})",
        kMaterials));
    ASSERT_TRUE(load.ok()) << load.errors.front();
    const SceneFile& s = load.scene;
    ASSERT_EQ(s.materials.size(), 3u);
    ASSERT_EQ(s.objects.size(), 3u);
    const ContactMaterial& enamel = s.materials[size_t(s.objects[0].material)];
    EXPECT_EQ(enamel.name, "enamel");
    EXPECT_FALSE(enamel.compliant);
    EXPECT_EQ(enamel.friction_static, 0.2);
    EXPECT_EQ(enamel.friction_kinetic, 0.1);
    const ContactMaterial& gum = s.materials[size_t(s.objects[1].material)];
    EXPECT_TRUE(gum.compliant);
    ASSERT_EQ(gum.yield_curve.size(), 1u);
    EXPECT_DOUBLE_EQ(gum.yield_curve[0][1] / gum.yield_curve[0][0], 1.0 / 400.0);
    EXPECT_EQ(gum.friction_kinetic, 0.5);  // one coefficient given: both
    ASSERT_EQ(s.objects[1].regions.size(), 1u);
    const MaterialRegion& r = s.objects[1].regions[0];
    EXPECT_EQ(s.materials[size_t(r.material)].name, "floor");
    EXPECT_EQ(s.materials[size_t(r.material)].yield_curve.size(), 2u);
    EXPECT_DOUBLE_EQ(s.materials[size_t(r.material)].yield_curve[1][1], 0.08e-3);  // mm -> m
    EXPECT_DOUBLE_EQ(r.normal.y, 1.0);
    EXPECT_EQ(r.radius_m, 0.003);
    EXPECT_EQ(r.min_cos, 0.5);
    EXPECT_EQ(s.objects[2].material, -1);  // rigid and frictionless
}

TEST_F(SceneFileTest, BadMaterialsAreReportedAtTheirPlace) {
    const SceneLoad load = load_scene(scene(
        R"({"name": "a", "mesh": "meshes/cube.obj", "material": "nothing"},
           {"name": "b", "mesh": "meshes/cube.obj", "regions": [{"material": "soft", "center": [0, 0, 0]}]})",
        R"("materials": {
            "hard": {"kind": "rigid", "stiffness_N_per_m": 5},
            "soft": {"kind": "compliant", "yield_curve_N_mm": [[0, 0], [0.25, 0.05], [0.5, 0.3]]},
            "slippery": {"kind": "rigid", "friction_static": 0.1, "friction_kinetic": 0.4},
            "odd": {"kind": "jelly"},
            "vague": {"kind": "compliant"}
          },)"));
    EXPECT_TRUE(has_error(load, "scene.json", "/objects/0/material", "unknown material"));
    EXPECT_TRUE(has_error(load, "scene.json", "/objects/1/regions/0/radius", "positive"));
    EXPECT_TRUE(has_error(load, "scene.json", "/materials/hard", "rigid material"));
    EXPECT_TRUE(has_error(load, "scene.json", "/materials/soft/yield_curve_N_mm/2", "softens"));
    EXPECT_TRUE(has_error(load, "scene.json", "/materials/slippery/friction_kinetic", "exceeds"));
    EXPECT_TRUE(has_error(load, "scene.json", "/materials/odd/kind", "jelly"));
    EXPECT_TRUE(has_error(load, "scene.json", "/materials/vague", "exactly one"));
}

TEST_F(SceneFileTest, MissingTrajectoryFile) {
    const SceneLoad load = load_scene(scene(kObject, "", R"("tool": {"name": "probe", "mesh": "meshes/cube.obj"},)",
                                            R"("trajectory": "nope.csv")"));
    EXPECT_TRUE(has_error(load, "scene.json", "/trajectory", "not found"));
    std::vector<std::string> errors;
    EXPECT_TRUE(load_trajectory(path("nope.csv"), errors).empty());
    ASSERT_EQ(errors.size(), 1u);
    EXPECT_NE(errors[0].find("nope.csv"), std::string::npos);
}

// Loads a CSV through the scene, so the errors arrive as the CLI would print them.
class TrajectoryTest : public SceneFileTest {
protected:
    SceneLoad load(const std::string& csv) {
        write("traj.csv", csv);
        return load_scene(scene(kObject));
    }
};

TEST_F(TrajectoryTest, WhitespaceTolerantHeaderAndCrlf) {
    const SceneLoad l = load(" t , x,y ,z,\tqw,qx,qy,qz \r\n0, 0,0,0, 1,0,0,0\r\n1,+1,0,0,1,0,0,0\r\n\r\n");
    ASSERT_TRUE(l.ok()) << l.errors.front();
    ASSERT_EQ(l.scene.trajectory.size(), 2u);
    EXPECT_EQ(l.scene.trajectory[1].pose.position.x, 1.0);
}

TEST_F(TrajectoryTest, BadHeader) {
    const SceneLoad l = load("time,x,y,z,qw,qx,qy,qz\n0,0,0,0,1,0,0,0\n1,0,0,0,1,0,0,0\n");
    EXPECT_TRUE(has_error(l, "traj.csv", "line 1", "header"));
}

TEST_F(TrajectoryTest, EmptyFile) {
    const SceneLoad l = load("");
    EXPECT_TRUE(has_error(l, "traj.csv", "line 1", "empty"));
}

TEST_F(TrajectoryTest, NanValue) {
    const SceneLoad l = load("t,x,y,z,qw,qx,qy,qz\n0,0,0,0,1,0,0,0\n1,0,0,0,1,nan,0,0\n2,0,0,0,1,0,0,0\n");
    EXPECT_TRUE(has_error(l, "traj.csv", "line 3: column qx", "not a number"));
}

TEST_F(TrajectoryTest, GarbageAndMissingValues) {
    const SceneLoad l = load("t,x,y,z,qw,qx,qy,qz\n0,0,0,0,1,0,0,0\n1,0,1.5e,0,1,0,0,0\n2,0,0,0,1,0,0\n");
    EXPECT_TRUE(has_error(l, "traj.csv", "line 3: column y", "not a number"));
    EXPECT_TRUE(has_error(l, "traj.csv", "line 4", "expected 8 values, found 7"));
}

TEST_F(TrajectoryTest, TimeGoingBackwards) {
    const SceneLoad l = load("t,x,y,z,qw,qx,qy,qz\n0,0,0,0,1,0,0,0\n1,0,0,0,1,0,0,0\n0.5,0,0,0,1,0,0,0\n");
    EXPECT_TRUE(has_error(l, "traj.csv", "line 4", "time 0.5 is not after the previous 1"));
}

TEST_F(TrajectoryTest, DuplicateTime) {
    const SceneLoad l = load("t,x,y,z,qw,qx,qy,qz\n0.5,0,0,0,1,0,0,0\n0.5,0,0,0,1,0,0,0\n");
    EXPECT_TRUE(has_error(l, "traj.csv", "line 3", "time 0.5 is not after the previous 0.5"));
}

TEST_F(TrajectoryTest, OneRowOnly) {
    const SceneLoad l = load("t,x,y,z,qw,qx,qy,qz\n0,0,0,0,1,0,0,0\n");
    EXPECT_TRUE(has_error(l, "traj.csv", "line 2", "at least 2 rows"));
}

TEST_F(TrajectoryTest, NonUnitQuaternion) {
    const SceneLoad l = load("t,x,y,z,qw,qx,qy,qz\n0,0,0,0,1,0,0,0\n1,0,0,0,1,0.1,0,0\n");
    EXPECT_TRUE(has_error(l, "traj.csv", "line 3", "quaternion"));
}

TEST_F(TrajectoryTest, NearlyUnitQuaternionIsNormalised) {
    const SceneLoad l = load("t,x,y,z,qw,qx,qy,qz\n0,0,0,0,1.0005,0,0,0\n1,0,0,0,0,0.9995,0,0\n");
    ASSERT_TRUE(l.ok()) << l.errors.front();
    EXPECT_EQ(l.scene.trajectory[0].pose.orientation, Quat(1, 0, 0, 0));
    EXPECT_EQ(l.scene.trajectory[1].pose.orientation, Quat(0, 1, 0, 0));
}

TEST_F(TrajectoryTest, SignsMadeContinuous) {
    // Rows 2 and 3 are the same rotation as their neighbours' short-way continuation, written
    // with the opposite sign.
    const double c = std::cos(0.1), s = std::sin(0.1);
    const std::string row2 = "1,0,0,0," + std::to_string(-c) + ",0," + std::to_string(-s) + ",0\n";
    const SceneLoad l = load("t,x,y,z,qw,qx,qy,qz\n0,0,0,0,1,0,0,0\n" + row2 + "2,0,0,0,-1,0,0,0\n");
    ASSERT_TRUE(l.ok()) << l.errors.front();
    const auto& tr = l.scene.trajectory;
    for (size_t i = 1; i < tr.size(); ++i) EXPECT_GT(glm::dot(tr[i - 1].pose.orientation, tr[i].pose.orientation), 0.0);
    EXPECT_GT(tr[1].pose.orientation.w, 0.0);
    EXPECT_EQ(tr[2].pose.orientation, Quat(1, 0, 0, 0));
}

TEST_F(TrajectoryTest, ManyBadRowsAreCapped) {
    std::string csv = "t,x,y,z,qw,qx,qy,qz\n";
    for (int i = 0; i < 1000; ++i) csv += "x,0,0,0,1,0,0,0\n";
    const SceneLoad l = load(csv);
    EXPECT_LE(l.errors.size(), 60u);
    EXPECT_TRUE(has_error(l, "traj.csv", "more faults not shown"));
}

std::vector<TrajectorySample> turn_90_about_y() {
    TrajectorySample a, b;
    a.t = 1.0;
    a.pose.position = Vec3(0, 0, 0);
    b.t = 3.0;
    b.pose.position = Vec3(2, -4, 6);
    b.pose.orientation = glm::angleAxis(glm::radians(90.0), Vec3(0, 1, 0));
    return {a, b};
}

TEST(SampleTrajectory, ExactAtRows) {
    const auto tr = turn_90_about_y();
    size_t cursor = 0;
    for (const auto& row : tr) {
        const Pose p = sample_trajectory(tr, row.t, cursor);
        EXPECT_EQ(p.position, row.pose.position);
        EXPECT_EQ(p.orientation, row.pose.orientation);
    }
}

TEST(SampleTrajectory, LinearPositionMidway) {
    const auto tr = turn_90_about_y();
    size_t cursor = 0;
    const Pose p = sample_trajectory(tr, 2.0, cursor);
    EXPECT_NEAR(glm::distance(p.position, Vec3(1, -2, 3)), 0.0, 1e-15);
    const Pose q = sample_trajectory(tr, 1.5, cursor);
    EXPECT_NEAR(glm::distance(q.position, Vec3(0.5, -1, 1.5)), 0.0, 1e-15);
}

TEST(SampleTrajectory, SlerpMidwayOfA90DegreeTurnIs45Degrees) {
    const auto tr = turn_90_about_y();
    size_t cursor = 0;
    const Quat q = sample_trajectory(tr, 2.0, cursor).orientation;
    EXPECT_NEAR(glm::length(q), 1.0, 1e-15);
    EXPECT_NEAR(glm::degrees(glm::angle(q)), 45.0, 1e-9);
    const Vec3 axis = glm::axis(q);
    EXPECT_NEAR(axis.y, 1.0, 1e-12);
    // A quarter of the way: 22.5 degrees (slerp is uniform in angle, unlike lerp).
    EXPECT_NEAR(glm::degrees(glm::angle(sample_trajectory(tr, 1.5, cursor).orientation)), 22.5, 1e-9);
}

TEST(SampleTrajectory, ClampedAtBothEnds) {
    const auto tr = turn_90_about_y();
    size_t cursor = 0;
    EXPECT_EQ(sample_trajectory(tr, -10.0, cursor).position, tr.front().pose.position);
    EXPECT_EQ(sample_trajectory(tr, 1e9, cursor).position, tr.back().pose.position);
    EXPECT_EQ(sample_trajectory(tr, std::nan(""), cursor).position, tr.front().pose.position);
}

TEST(SampleTrajectory, CursorGivesTheSameAnswerInAnyOrder) {
    std::vector<TrajectorySample> tr;
    for (int i = 0; i < 50; ++i) {
        TrajectorySample s;
        s.t = 0.1 * i + 0.01 * (i % 3);
        s.pose.position = Vec3(std::sin(i), i, -i);
        s.pose.orientation = glm::angleAxis(0.05 * i, glm::normalize(Vec3(1, 2, 3)));
        tr.push_back(s);
    }
    size_t forward = 0, wild = 0;
    for (int k = 0; k <= 600; ++k) {
        const double t = -0.2 + 0.009 * k;
        size_t fresh = 0;
        const Pose expected = sample_trajectory(tr, t, fresh);  // binary search from 0
        const Pose a = sample_trajectory(tr, t, forward);       // monotone cursor
        wild = (wild * 7919 + 13) % 97;                          // a cursor pointing anywhere
        const Pose b = sample_trajectory(tr, t, wild);
        EXPECT_EQ(a.position, expected.position) << t;
        EXPECT_EQ(a.orientation, expected.orientation) << t;
        EXPECT_EQ(b.position, expected.position) << t;
        EXPECT_EQ(b.orientation, expected.orientation) << t;
    }
}

TEST(SampleTrajectory, EmptyAndSingleRow) {
    size_t cursor = 0;
    EXPECT_EQ(sample_trajectory({}, 1.0, cursor).orientation, Quat(1, 0, 0, 0));
    TrajectorySample s;
    s.t = 2.0;
    s.pose.position = Vec3(1, 2, 3);
    EXPECT_EQ(sample_trajectory({s}, 5.0, cursor).position, Vec3(1, 2, 3));
}

}  // namespace
}  // namespace sulcus

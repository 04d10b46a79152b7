// sulcus-cli replay: recorded lessons replayed headless, scored, checked, reported.
#include "cli/commands.h"
#include "sulcus/app/lesson_session.h"
#include "sulcus/app/text.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

namespace fs = std::filesystem;

namespace sulcus::cli {

const char* const kHelpReplay =
    "usage: sulcus-cli replay RECORDING|FOLDER... [--lesson FILE] [--report FILE.json|FILE.html]\n"
    "                         [--out DIR] [--check] [--jobs N] [--shard I/N] [--junit FILE]\n"
    "                         [--content-root DIR] [--cases DIR]\n"
    "\n"
    "Replays recorded lesson sessions (sulcus.recording/2) headless: every recorded tick goes\n"
    "through the servo tick (device pose -> step -> safety layer) and the lesson runtime, with\n"
    "the trainee's UI events at the ticks they were taken, and the lesson is scored again from\n"
    "its rubric. Deterministic: the same recording, lesson and case give the same report, byte\n"
    "for byte. A FOLDER stands for every *.rec file in it (sorted by name).\n"
    "\n"
    "  --lesson FILE        score against this lesson (default: the one the recording names,\n"
    "                       relative to the content root)\n"
    "  --report FILE        one recording: write its report as JSON (.json) or as an HTML page\n"
    "                       (.html) with the chart, per-site scores and force over time\n"
    "  --out DIR            write NAME.json and NAME.html for every recording into DIR\n"
    "  --check              compare the recomputed scores (and the replayed forces) with the\n"
    "                       ones stored in each recording; exit 1 naming the first difference\n"
    "  --jobs N             replay N recordings at a time (default 1)\n"
    "  --shard I/N          replay only the I-th of N shares of the recordings (1 <= I <= N):\n"
    "                       those whose position in the sorted list is I-1 modulo N\n"
    "  --junit FILE         a JUnit XML summary, one test case per recording\n"
    "  --content-root DIR   where lessons and charts are (default: content/assets of the\n"
    "                       sources the binary was built from)\n"
    "  --cases DIR          where the built cases are (default: cases/ next to bin/)\n"
    "\n"
    "Prints one line per recording. Exit 0 done; 1 a check failed; 2 bad input (a recording,\n"
    "lesson or case that cannot be read, named with the place).\n";

namespace {

struct Job {
    std::string path;
    LessonReplay replay;
    std::string check;  // --check: "" or the first difference
    std::string write_error;
    double seconds = 0.0;
};

std::string write_report(const LessonOutcome& o, const std::string& path) {
    const std::string ext = fs::path(path).extension().string();
    if (ext == ".html" || ext == ".htm") return write_file_atomic(path, report_html(o));
    return write_file_atomic(path, report_json(o).dump(2) + "\n");
}

}  // namespace

int cmd_replay(const std::vector<std::string>& args) {
    std::vector<std::string> inputs;
    std::string report, out_dir, junit;
    ReplayOptions options;
    bool check = false;
    int jobs = 1, shard_i = 1, shard_n = 1;
    for (size_t i = 0; i < args.size(); ++i) {
        auto value = [&](const char* what) -> const std::string* {
            if (i + 1 >= args.size()) {
                usage("replay: " + args[i] + " needs " + what);
                return nullptr;
            }
            return &args[++i];
        };
        const std::string& a = args[i];
        const std::string* v = nullptr;
        if (a == "--lesson") {
            if (!(v = value("a file"))) return kUsage;
            options.lesson_path = *v;
        } else if (a == "--report") {
            if (!(v = value("a file"))) return kUsage;
            report = *v;
        } else if (a == "--out") {
            if (!(v = value("a folder"))) return kUsage;
            out_dir = *v;
        } else if (a == "--junit") {
            if (!(v = value("a file"))) return kUsage;
            junit = *v;
        } else if (a == "--content-root") {
            if (!(v = value("a folder"))) return kUsage;
            options.content_root = *v;
        } else if (a == "--cases") {
            if (!(v = value("a folder"))) return kUsage;
            options.cases_dir = *v;
        } else if (a == "--check") {
            check = true;
        } else if (a == "--jobs") {
            if (!(v = value("a number"))) return kUsage;
            long n = 0;
            if (!parse_whole(*v, 1, 256, &n)) return usage("replay: --jobs: '" + *v + "' is not 1..256");
            jobs = static_cast<int>(n);
        } else if (a == "--shard") {
            if (!(v = value("I/N"))) return kUsage;
            int si = 0, sn = 0;
            char tail = 0;
            if (std::sscanf(v->c_str(), "%d/%d%c", &si, &sn, &tail) != 2 || sn < 1 || si < 1 || si > sn)
                return usage("replay: --shard: '" + *v + "' is not I/N with 1 <= I <= N");
            shard_i = si;
            shard_n = sn;
        } else if (!a.empty() && a[0] == '-') {
            return usage("replay: unknown option '" + a + "'");
        } else {
            inputs.push_back(a);
        }
    }
    if (inputs.empty()) return usage("replay: no recording given");

    // Recordings: files as given, folders expanded to their *.rec files, then the shard's share.
    std::vector<std::string> all;
    for (const std::string& in : inputs) {
        std::error_code ec;
        if (fs::is_directory(in, ec)) {
            std::vector<std::string> found;
            for (const auto& e : fs::directory_iterator(in, ec))
                if (e.is_regular_file() && e.path().extension() == ".rec") found.push_back(e.path().string());
            std::sort(found.begin(), found.end());
            if (found.empty()) {
                std::fprintf(stderr, "%s: no recordings (*.rec) in this folder\n", in.c_str());
                return kUsage;
            }
            all.insert(all.end(), found.begin(), found.end());
        } else {
            all.push_back(in);
        }
    }
    std::vector<Job> work;
    for (std::size_t k = 0; k < all.size(); ++k)
        if (static_cast<int>(k % static_cast<std::size_t>(shard_n)) == shard_i - 1) work.push_back(Job{all[k], {}, {}, {}, 0.0});
    if (!report.empty() && work.size() != 1)
        return usage("replay: --report writes one recording's report; use --out DIR for " + std::to_string(work.size()));
    if (!out_dir.empty()) {
        std::error_code ec;
        fs::create_directories(out_dir, ec);
        if (ec) {
            std::fprintf(stderr, "%s: cannot create the folder (%s)\n", out_dir.c_str(), ec.message().c_str());
            return kUsage;
        }
    }

    std::atomic<std::size_t> next{0};
    auto worker = [&]() {
        for (std::size_t k; (k = next.fetch_add(1)) < work.size();) {
            Job& j = work[k];
            const auto t0 = std::chrono::steady_clock::now();
            j.replay = replay_lesson(j.path, options);
            if (j.replay.ok()) {
                if (check) j.check = check_outcome(j.replay.outcome);
                if (!report.empty()) j.write_error = write_report(j.replay.outcome, report);
                if (!out_dir.empty() && j.write_error.empty()) {
                    const std::string stem = (fs::path(out_dir) / fs::path(j.path).stem()).string();
                    j.write_error = write_report(j.replay.outcome, stem + ".json");
                    if (j.write_error.empty()) j.write_error = write_report(j.replay.outcome, stem + ".html");
                }
            }
            j.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        }
    };
    std::vector<std::thread> threads;
    const int n_threads = std::min<int>(jobs, static_cast<int>(work.size()));
    for (int t = 1; t < n_threads; ++t) threads.emplace_back(worker);
    worker();
    for (std::thread& t : threads) t.join();

    int status = kOk;
    int failures = 0, errors = 0;
    double total_s = 0.0;
    for (const Job& j : work) {
        total_s += j.seconds;
        if (!j.replay.ok()) {
            std::fprintf(stderr, "%s\n", j.replay.error.c_str());
            status = kUsage;
            ++errors;
            continue;
        }
        if (!j.write_error.empty()) {
            std::fprintf(stderr, "%s\n", j.write_error.c_str());
            status = kUsage;
            ++errors;
            continue;
        }
        const LessonOutcome& o = j.replay.outcome;
        std::printf("%s: %s: score %.3f (%s), charted %d/%d, %llu ticks replayed%s%s\n", j.path.c_str(),
                    o.lesson.title.c_str(), o.scores.overall, o.scores.passed ? "passed" : "not passed",
                    o.scores.sites_charted, o.scores.sites_target, static_cast<unsigned long long>(o.ticks),
                    o.first_mismatch < 0 ? ", forces as recorded" : ", forces differ from the recording",
                    check ? (j.check.empty() ? ", check passed" : ", CHECK FAILED") : "");
        if (check && !j.check.empty()) {
            std::fprintf(stderr, "%s: %s\n", j.path.c_str(), j.check.c_str());
            ++failures;
            if (status == kOk) status = kFailed;
        }
    }

    if (!junit.empty()) {
        std::string x = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
        char head[256];
        std::snprintf(head, sizeof head, "<testsuite name=\"sulcus.replay\" tests=\"%zu\" failures=\"%d\" errors=\"%d\" time=\"%.3f\">\n",
                      work.size(), failures, errors, total_s);
        x += head;
        for (const Job& j : work) {
            char t[64];
            std::snprintf(t, sizeof t, "%.3f", j.seconds);
            x += "  <testcase classname=\"replay\" name=\"" + xml_escape(j.path) + "\" time=\"" + t + "\">";
            if (!j.replay.ok()) {
                x += "<error message=\"" + xml_escape(j.replay.error) + "\"/>";
            } else if (!j.write_error.empty()) {
                x += "<error message=\"" + xml_escape(j.write_error) + "\"/>";
            } else if (check && !j.check.empty()) {
                x += "<failure message=\"" + xml_escape(j.check) + "\"/>";
            } else {
                const LessonOutcome& o = j.replay.outcome;
                char s[160];
                std::snprintf(s, sizeof s, "score %.3f (%s), charted %d/%d", o.scores.overall,
                              o.scores.passed ? "passed" : "not passed", o.scores.sites_charted, o.scores.sites_target);
                x += "<system-out>" + xml_escape(s) + "</system-out>";
            }
            x += "</testcase>\n";
        }
        x += "</testsuite>\n";
        if (std::string err = write_file_atomic(junit, x); !err.empty()) {
            std::fprintf(stderr, "%s\n", err.c_str());
            return kUsage;
        }
    }
    return status;
}

}  // namespace sulcus::cli

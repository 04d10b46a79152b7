// sulcus-cli lesson: check a lesson, write a starter one, record one with the simulated hand.
#include "cli/commands.h"
#include "sulcus/app/lesson_session.h"

#include <cstdio>
#include <string>
#include <vector>

namespace sulcus::cli {

const char* const kHelpLesson =
    "usage: sulcus-cli lesson check FILE [--content-root DIR] [--cases DIR] [--no-case]\n"
    "       sulcus-cli lesson new --case DIR [--out FILE] [--title TEXT] [--content-root DIR]\n"
    "       sulcus-cli lesson record FILE --out RECORDING [--content-root DIR] [--cases DIR]\n"
    "\n"
    "check   validates a lesson (sulcus.lesson/1, docs/lessons.md): its JSON, every key and value,\n"
    "        the limits, that its chart lies inside the content root and reads, and (unless\n"
    "        --no-case) that the case built from that chart is there, current and built for the\n"
    "        lesson's probe. Prints every fault, one line each naming the file and the JSON path.\n"
    "new     writes a starter lesson for a case folder (one holding chart.json, e.g.\n"
    "        content/assets/cases/healthy_11 or a built case): two steps per tooth (facial,\n"
    "        lingual), the usual force and sulcus rules, the default rubric. To FILE, or to the\n"
    "        standard output without --out.\n"
    "record  records the lesson done by the simulated hand on the servo loop's manual clock (the\n"
    "        case's probing trajectory; it charts each site as it rests on the floor), scores it\n"
    "        and stores the scores in the recording, for `sulcus-cli replay --check`.\n"
    "\n"
    "  --content-root DIR  the folder lesson paths are relative to (default: the parent of the\n"
    "                      lesson's folder; for new, content/assets of the sources)\n"
    "  --cases DIR         where the built cases are (default: cases/ next to bin/)\n"
    "\n"
    "Exit 0 done; 2 bad input (every fault printed).\n";

namespace {

int lesson_check(const std::vector<std::string>& args) {
    std::string file, root, cases;
    bool with_case = true;
    for (size_t i = 0; i < args.size(); ++i) {
        if (args[i] == "--content-root" && i + 1 < args.size()) root = args[++i];
        else if (args[i] == "--cases" && i + 1 < args.size()) cases = args[++i];
        else if (args[i] == "--no-case") with_case = false;
        else if (!args[i].empty() && args[i][0] == '-') return usage("lesson check: unknown or incomplete option '" + args[i] + "'");
        else if (file.empty()) file = args[i];
        else return usage("lesson check: more than one file given ('" + args[i] + "')");
    }
    if (file.empty()) return usage("lesson check: no lesson file given");
    const LessonLoad load = load_lesson(file, root);
    for (const std::string& e : load.errors) std::fprintf(stderr, "%s\n", e.c_str());
    if (!load.ok()) return kUsage;
    std::string case_note;
    if (with_case) {
        const LessonCase c = load_lesson_case(load, cases.empty() ? default_cases_dir() : cases);
        if (!c.ok()) {
            std::fprintf(stderr, "%s\n", c.error.c_str());
            return kUsage;
        }
        case_note = ", case " + c.dir;
    }
    std::printf("%s: ok: '%s', %zu steps, %zu target sites, %zu rules%s\n", file.c_str(), load.lesson.title.c_str(),
                load.lesson.steps.size(), load.lesson.target_sites().size(), load.lesson.rules.size(), case_note.c_str());
    return kOk;
}

int lesson_new(const std::vector<std::string>& args) {
    std::string case_dir, out, title, root;
    for (size_t i = 0; i < args.size(); ++i) {
        if (args[i] == "--case" && i + 1 < args.size()) case_dir = args[++i];
        else if (args[i] == "--out" && i + 1 < args.size()) out = args[++i];
        else if (args[i] == "--title" && i + 1 < args.size()) title = args[++i];
        else if (args[i] == "--content-root" && i + 1 < args.size()) root = args[++i];
        else return usage("lesson new: unknown or incomplete argument '" + args[i] + "'");
    }
    if (case_dir.empty()) return usage("lesson new: no case given (--case DIR)");
    if (root.empty()) root = default_content_root();
    std::string error;
    const std::string chart_path = lesson_chart_path(case_dir, root, &error);
    if (chart_path.empty()) {
        std::fprintf(stderr, "%s\n", error.c_str());
        return kUsage;
    }
    const ChartLoad chart = load_chart(root + "/" + chart_path);
    if (!chart.ok()) {
        for (const std::string& e : chart.errors) std::fprintf(stderr, "%s\n", e.c_str());
        return kUsage;
    }
    std::string teeth;
    for (const auto& [fdi, t] : chart.chart.teeth) teeth += (teeth.empty() ? "" : ", ") + std::to_string(fdi);
    const Lesson lesson = starter_lesson(chart.chart, chart_path, title.empty() ? "Charting " + teeth : title);
    const std::string text = lesson_to_json(lesson).dump(2) + "\n";
    if (out.empty()) {
        std::fputs(text.c_str(), stdout);
        return kOk;
    }
    if (std::string err = write_file_atomic(out, text); !err.empty()) {
        std::fprintf(stderr, "%s\n", err.c_str());
        return kUsage;
    }
    std::printf("%s: a starter lesson for %s (%zu steps)\n", out.c_str(), chart_path.c_str(), lesson.steps.size());
    return kOk;
}

int lesson_record(const std::vector<std::string>& args) {
    std::string file, out;
    HandRecordOptions options;
    for (size_t i = 0; i < args.size(); ++i) {
        if (args[i] == "--out" && i + 1 < args.size()) out = args[++i];
        else if (args[i] == "--content-root" && i + 1 < args.size()) options.content_root = args[++i];
        else if (args[i] == "--cases" && i + 1 < args.size()) options.cases_dir = args[++i];
        else if (!args[i].empty() && args[i][0] == '-') return usage("lesson record: unknown or incomplete option '" + args[i] + "'");
        else if (file.empty()) file = args[i];
        else return usage("lesson record: more than one lesson given ('" + args[i] + "')");
    }
    if (file.empty()) return usage("lesson record: no lesson file given");
    if (out.empty()) return usage("lesson record: no recording given (--out FILE)");
    LessonOutcome o;
    if (std::string err = record_lesson_with_hand(file, out, options, &o); !err.empty()) {
        std::fprintf(stderr, "%s\n", err.c_str());
        return kUsage;
    }
    std::printf("%s: %s: %llu ticks, score %.3f (%s), charted %d/%d\n", out.c_str(), o.lesson.title.c_str(),
                static_cast<unsigned long long>(o.ticks), o.scores.overall, o.scores.passed ? "passed" : "not passed",
                o.scores.sites_charted, o.scores.sites_target);
    return kOk;
}

}  // namespace

int cmd_lesson(const std::vector<std::string>& args) {
    if (args.empty()) return usage("lesson: which? check, new or record");
    const std::vector<std::string> rest(args.begin() + 1, args.end());
    if (args[0] == "check") return lesson_check(rest);
    if (args[0] == "new") return lesson_new(rest);
    if (args[0] == "record") return lesson_record(rest);
    return usage("lesson: unknown subcommand '" + args[0] + "' (check, new, record)");
}

}  // namespace sulcus::cli

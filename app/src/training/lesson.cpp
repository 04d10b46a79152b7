// Reading and writing lesson scripts, `sulcus.lesson/1` (docs/lessons.md).
//
// The reader never stops at the first fault: every check appends one line "FILE: JSON path: what"
// and carries on with what it could read, so an author sees all the faults of a file at once.
#include "sulcus/app/lesson.h"

#include "sulcus/content/chart.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <optional>
#include <set>
#include <sstream>

namespace sulcus {

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

// ---- names ----------------------------------------------------------------------------------

constexpr StepOrder kOrders[] = {StepOrder::Any, StepOrder::Listed};
constexpr StepCondition kConditions[] = {StepCondition::Charted, StepCondition::Probed, StepCondition::Walked,
                                         StepCondition::Acknowledged};
constexpr RuleTrigger kTriggers[] = {RuleTrigger::ForceAbove, RuleTrigger::ForceAtLeast, RuleTrigger::LeftSulcus};
constexpr RuleLevel kLevels[] = {RuleLevel::Note, RuleLevel::Warning};

// The names of an enum's values as "\"a\", \"b\" or \"c\"", for messages.
template <class E, std::size_t N>
std::string choices(const E (&values)[N], const char* (*name)(E)) {
    std::string s;
    for (std::size_t i = 0; i < N; ++i) {
        if (i > 0) s += (i + 1 == N) ? " or " : ", ";
        s += std::string("\"") + name(values[i]) + "\"";
    }
    return s;
}

template <class E, std::size_t N>
bool parse_enum(const std::string& text, const E (&values)[N], const char* (*name)(E), E* out) {
    for (E v : values)
        if (text == name(v)) {
            *out = v;
            return true;
        }
    return false;
}

// ---- messages -------------------------------------------------------------------------------

// A value as written, short and on one line (dump escapes control characters).
std::string shown(const json& v) {
    std::string s = v.dump(-1, ' ', false, json::error_handler_t::replace);
    if (s.size() > 60) s = s.substr(0, 57) + "...";
    return s;
}
std::string quote_text(const std::string& s) { return shown(json(s)); }

std::string one_line(std::string s) {
    std::replace(s.begin(), s.end(), '\n', ' ');
    std::replace(s.begin(), s.end(), '\r', ' ');
    return s;
}

std::string type_of(const json& v) {
    if (v.is_null()) return "null";
    if (v.is_boolean()) return "a boolean";
    if (v.is_number()) return "a number";
    if (v.is_string()) return "a string";
    if (v.is_array()) return "an array";
    return "an object";
}
std::string found(const json& v) {
    return v.is_array() || v.is_object() ? type_of(v) : shown(v);
}

std::string key_path(const std::string& path, const std::string& key) { return path.empty() ? key : path + "." + key; }
std::string index_path(const std::string& path, std::size_t i) { return path + "[" + std::to_string(i) + "]"; }

// Characters of a UTF-8 string (code points), for the text limit.
std::size_t characters(const std::string& s) {
    return std::size_t(std::count_if(s.begin(), s.end(), [](char c) { return (static_cast<unsigned char>(c) & 0xC0) != 0x80; }));
}

std::string fmt(double v) {
    std::ostringstream o;
    o << v;
    return o.str();
}

// Collects "SOURCE: path: what" lines.
struct Faults {
    std::string source;
    std::vector<std::string>* out;
    void add(const std::string& path, const std::string& what) const {
        out->push_back(one_line(path.empty() ? source + ": " + what : source + ": " + path + ": " + what));
    }
};

// ---- reading values -------------------------------------------------------------------------

// Unknown keys are errors: a misspelt key would otherwise silently keep a default.
void check_keys(const Faults& f, const json& obj, const std::string& path, const std::vector<const char*>& allowed) {
    std::string list;
    for (const char* a : allowed) list += std::string(list.empty() ? "" : ", ") + a;
    for (auto it = obj.begin(); it != obj.end(); ++it) {
        if (std::find_if(allowed.begin(), allowed.end(), [&](const char* a) { return it.key() == a; }) != allowed.end())
            continue;
        f.add(path, "unknown key " + quote_text(it.key()) + " (allowed: " + list + ")");
    }
}

const json* member(const json& obj, const char* key) {
    const auto it = obj.find(key);
    return it == obj.end() ? nullptr : &*it;
}

// A string member; false (with a fault) when present but wrong, or absent and required.
bool read_string(const Faults& f, const json& obj, const char* key, const std::string& path, bool required,
                 bool allow_empty, std::string* out) {
    const std::string here = key_path(path, key);
    const json* v = member(obj, key);
    if (!v) {
        if (required) f.add(here, "missing (a string is required)");
        return false;
    }
    if (!v->is_string()) {
        f.add(here, "expected a string, found " + found(*v));
        return false;
    }
    const std::string& s = v->get_ref<const std::string&>();
    if (characters(s) > kMaxLessonText) {
        f.add(here, std::to_string(characters(s)) + " characters, longer than the " + std::to_string(kMaxLessonText) +
                        " allowed");
        return false;
    }
    if (!allow_empty && s.empty()) {
        f.add(here, "must not be empty");
        return false;
    }
    *out = s;
    return true;
}

// A finite number member in [lo, hi]; absent keeps *out.
bool read_number(const Faults& f, const json& obj, const char* key, const std::string& path, double lo, double hi,
                 double* out, const char* unit = "") {
    const json* v = member(obj, key);
    if (!v) return false;
    const std::string here = key_path(path, key);
    if (!v->is_number()) {
        f.add(here, "expected a number, found " + found(*v));
        return false;
    }
    const double x = v->get<double>();
    if (!std::isfinite(x) || x < lo || x > hi) {
        std::string range = std::isinf(hi) ? "at least " + fmt(lo) : "from " + fmt(lo) + " to " + fmt(hi);
        f.add(here, shown(*v) + " is out of range (expected " + range + unit + ")");
        return false;
    }
    *out = x;
    return true;
}

bool as_integer(const json& v, std::int64_t* out) {
    if (v.is_number_unsigned()) {
        const std::uint64_t u = v.get<std::uint64_t>();
        if (u > std::uint64_t(INT64_MAX)) return false;
        *out = std::int64_t(u);
        return true;
    }
    if (v.is_number_integer()) {
        *out = v.get<std::int64_t>();
        return true;
    }
    return false;
}

// An array member no longer than `limit`; nullptr when absent or faulty.
const json* read_array(const Faults& f, const json& obj, const char* key, const std::string& path, std::size_t limit,
                       const char* what) {
    const json* v = member(obj, key);
    if (!v) return nullptr;
    const std::string here = key_path(path, key);
    if (!v->is_array()) {
        f.add(here, "expected an array, found " + found(*v));
        return nullptr;
    }
    if (v->size() > limit) {
        f.add(here, std::to_string(v->size()) + " " + what + ", more than the " + std::to_string(limit) + " allowed");
        return nullptr;
    }
    return v;
}

bool valid_fdi(std::int64_t n) { return n >= 11 && n <= 48 && n % 10 >= 1 && n % 10 <= 8; }

// ---- the document's parts -------------------------------------------------------------------

void read_hint(const Faults& f, const json& v, const std::string& path, LessonHint* h) {
    if (v.is_string()) {  // shorthand: the text, shown after the default delay
        const std::string& text = v.get_ref<const std::string&>();
        if (text.empty())
            f.add(path, "must not be empty");
        else if (characters(text) > kMaxLessonText)
            f.add(path, std::to_string(characters(text)) + " characters, longer than the " +
                            std::to_string(kMaxLessonText) + " allowed");
        else
            h->text = text;
        return;
    }
    if (!v.is_object()) {
        f.add(path, "expected a string or {\"text\", \"after_s\"}, found " + found(v));
        return;
    }
    check_keys(f, v, path, {"text", "after_s"});
    read_string(f, v, "text", path, true, false, &h->text);
    read_number(f, v, "after_s", path, 0.0, 86400.0, &h->after_s, " s");
}

// `teeth`: the lesson's teeth, or nullptr when they are unknown (the chart did not read).
void read_step(const Faults& f, const json& v, const std::string& path, const std::vector<int>* teeth,
               LessonStep* s) {
    if (!v.is_object()) {
        f.add(path, "expected an object, found " + found(v));
        return;
    }
    check_keys(f, v, path, {"id", "instruction", "sites", "order", "complete", "hints"});
    read_string(f, v, "id", path, true, false, &s->id);
    read_string(f, v, "instruction", path, true, false, &s->instruction);
    std::string name;
    if (read_string(f, v, "order", path, false, true, &name) &&
        !parse_enum(name, kOrders, step_order_name, &s->order))
        f.add(key_path(path, "order"), "unknown order " + quote_text(name) + " (expected " +
                                           choices(kOrders, step_order_name) + ")");
    if (read_string(f, v, "complete", path, false, true, &name) &&
        !parse_enum(name, kConditions, step_condition_name, &s->complete))
        f.add(key_path(path, "complete"), "unknown condition " + quote_text(name) + " (expected " +
                                              choices(kConditions, step_condition_name) + ")");
    const std::string sites_path = key_path(path, "sites");
    const std::string needs = std::string("a \"") + step_condition_name(s->complete) +
                              "\" step needs target sites (only an \"acknowledged\" step may have none)";
    const bool need_sites = s->complete != StepCondition::Acknowledged;
    if (!member(v, "sites")) {
        if (need_sites) f.add(sites_path, "missing: " + needs);
    } else if (const json* a = read_array(f, v, "sites", path, kMaxStepSites, "sites")) {
        if (a->empty() && need_sites) f.add(sites_path, "empty: " + needs);
        for (std::size_t i = 0; i < a->size(); ++i) {
            const json& e = (*a)[i];
            const std::string here = index_path(sites_path, i);
            SiteRef ref;
            if (!e.is_string()) {
                f.add(here, "expected a site such as \"36MB\", found " + found(e));
                continue;
            }
            const std::string& text = e.get_ref<const std::string&>();
            if (!parse_site_ref(text, &ref)) {
                const bool number = text.size() >= 2 && std::isdigit(static_cast<unsigned char>(text[0])) &&
                                    std::isdigit(static_cast<unsigned char>(text[1]));
                if (number && !valid_fdi(std::stoi(text.substr(0, 2))))
                    f.add(here, quote_text(text) + ": " + text.substr(0, 2) + " is not an FDI tooth number (11-48)");
                else
                    f.add(here, quote_text(text) + " is not a site (expected an FDI tooth number and MB, B, DB, ML, L "
                                               "or DL, e.g. \"36MB\")");
                continue;
            }
            if (teeth && std::find(teeth->begin(), teeth->end(), ref.fdi) == teeth->end()) {
                std::string have;
                for (int t : *teeth) have += (have.empty() ? "" : ", ") + std::to_string(t);
                f.add(here, quote_text(text) + ": tooth " + std::to_string(ref.fdi) + " is not one of the lesson's teeth (" +
                                have + ")");
                continue;
            }
            const auto dup = std::find(s->sites.begin(), s->sites.end(), ref);
            if (dup != s->sites.end()) {
                f.add(here, quote_text(text) + " is listed twice in the step");
                continue;
            }
            s->sites.push_back(ref);
        }
    }
    const std::string hints_path = key_path(path, "hints");
    if (const json* a = read_array(f, v, "hints", path, kMaxStepHints, "hints"))
        for (std::size_t i = 0; i < a->size(); ++i) {
            LessonHint h;
            read_hint(f, (*a)[i], index_path(hints_path, i), &h);
            s->hints.push_back(h);
        }
}

void read_rule(const Faults& f, const json& v, const std::string& path, LessonRule* r) {
    if (!v.is_object()) {
        f.add(path, "expected an object, found " + found(v));
        return;
    }
    check_keys(f, v, path, {"id", "when", "threshold_N", "level", "message", "cooldown_s"});
    read_string(f, v, "id", path, true, false, &r->id);
    std::string name;
    bool when_ok = false;
    if (read_string(f, v, "when", path, true, true, &name)) {
        when_ok = parse_enum(name, kTriggers, rule_trigger_name, &r->when);
        if (!when_ok)
            f.add(key_path(path, "when"), "unknown trigger " + quote_text(name) + " (expected " +
                                              choices(kTriggers, rule_trigger_name) + ")");
    }
    if (when_ok) {
        const bool force = r->when != RuleTrigger::LeftSulcus;
        if (force && !member(v, "threshold_N"))
            f.add(key_path(path, "threshold_N"), std::string("missing (a \"") + rule_trigger_name(r->when) +
                                                     "\" rule needs a force in newtons)");
        if (!force && member(v, "threshold_N"))
            f.add(key_path(path, "threshold_N"), "not allowed for a \"left_sulcus\" rule (it watches no force)");
        if (force && member(v, "threshold_N")) {
            const json& t = *member(v, "threshold_N");
            if (t.is_number() && std::isfinite(t.get<double>()) && t.get<double>() <= 0.0)
                f.add(key_path(path, "threshold_N"), shown(t) + " is out of range (expected a force above 0 N)");
            else
                read_number(f, v, "threshold_N", path, 0.0, 100.0, &r->threshold_N, " N");
        }
    }
    if (read_string(f, v, "level", path, false, true, &name) && !parse_enum(name, kLevels, rule_level_name, &r->level))
        f.add(key_path(path, "level"), "unknown level " + quote_text(name) + " (expected " +
                                           choices(kLevels, rule_level_name) + ")");
    read_string(f, v, "message", path, true, false, &r->message);
    read_number(f, v, "cooldown_s", path, 0.0, 3600.0, &r->cooldown_s, " s");
}

// The rubric's fields by their C++ names; the ranges each must lie in.
struct RubricField {
    const char* name;
    double Rubric::*member;
    double lo, hi;
    const char* unit;
};
constexpr double kInf = INFINITY;
const RubricField kRubricFields[] = {
    {"depth_pass_mm", &Rubric::depth_pass_mm, 0.0, kMaxProbingDepthMm, " mm"},
    {"depth_exact_mm", &Rubric::depth_exact_mm, 0.0, kMaxProbingDepthMm, " mm"},
    {"depth_pass_fraction", &Rubric::depth_pass_fraction, 0.0, 1.0, ""},
    {"force_target_min_N", &Rubric::force_target_min_N, 0.0, 10.0, " N"},
    {"force_target_max_N", &Rubric::force_target_max_N, 0.0, 10.0, " N"},
    {"force_warning_N", &Rubric::force_warning_N, 0.0, 10.0, " N"},
    {"force_trauma_N", &Rubric::force_trauma_N, 0.0, 10.0, " N"},
    {"max_time_above_warning_s", &Rubric::max_time_above_warning_s, 0.0, kInf, " s"},
    {"angle_direct_max_deg", &Rubric::angle_direct_max_deg, 0.0, 90.0, " deg"},
    {"angle_interproximal_min_deg", &Rubric::angle_interproximal_min_deg, 0.0, 90.0, " deg"},
    {"angle_interproximal_max_deg", &Rubric::angle_interproximal_max_deg, 0.0, 90.0, " deg"},
    {"angle_pass_fraction", &Rubric::angle_pass_fraction, 0.0, 1.0, ""},
    {"walk_advance_mm", &Rubric::walk_advance_mm, 0.0, 50.0, " mm"},
    {"walk_pass_fraction", &Rubric::walk_pass_fraction, 0.0, 1.0, ""},
    {"completeness_pass_fraction", &Rubric::completeness_pass_fraction, 0.0, 1.0, ""},
    {"time_limit_s", &Rubric::time_limit_s, 0.0, kInf, " s"},
    {"weight_depth", &Rubric::weight_depth, 0.0, kInf, ""},
    {"weight_force", &Rubric::weight_force, 0.0, kInf, ""},
    {"weight_angulation", &Rubric::weight_angulation, 0.0, kInf, ""},
    {"weight_walking", &Rubric::weight_walking, 0.0, kInf, ""},
    {"weight_withdrawals", &Rubric::weight_withdrawals, 0.0, kInf, ""},
    {"weight_completeness", &Rubric::weight_completeness, 0.0, kInf, ""},
    {"weight_time", &Rubric::weight_time, 0.0, kInf, ""},
    {"pass_score", &Rubric::pass_score, 0.0, 1.0, ""},
};
constexpr const char* kWithdrawalsKey = "max_withdrawals_per_side";

void read_rubric(const Faults& f, const json& v, const std::string& path, Rubric* r) {
    if (!v.is_object()) {
        f.add(path, "expected an object, found " + found(v));
        return;
    }
    std::vector<const char*> allowed;
    for (const RubricField& fld : kRubricFields) allowed.push_back(fld.name);
    allowed.push_back(kWithdrawalsKey);
    check_keys(f, v, path, allowed);
    std::set<std::string> bad;  // fields with a fault: no pair check on them
    for (const RubricField& fld : kRubricFields)
        if (member(v, fld.name) && !read_number(f, v, fld.name, path, fld.lo, fld.hi, &(r->*fld.member), fld.unit))
            bad.insert(fld.name);
    if (const json* w = member(v, kWithdrawalsKey)) {
        std::int64_t n = 0;
        if (!as_integer(*w, &n) || n < 0 || n > 1000)
            f.add(key_path(path, kWithdrawalsKey), "expected a whole number from 0 to 1000, found " + found(*w));
        else
            r->max_withdrawals_per_side = int(n);
    }
    // Pairs that must be ordered.
    const auto ordered = [&](const char* lo, const char* hi, double a, double b) {
        if (bad.count(lo) || bad.count(hi) || a <= b) return;
        f.add(key_path(path, lo), fmt(a) + " is greater than " + hi + " (" + fmt(b) + ")");
    };
    ordered("depth_exact_mm", "depth_pass_mm", r->depth_exact_mm, r->depth_pass_mm);
    ordered("force_target_min_N", "force_target_max_N", r->force_target_min_N, r->force_target_max_N);
    ordered("force_warning_N", "force_trauma_N", r->force_warning_N, r->force_trauma_N);
    ordered("angle_interproximal_min_deg", "angle_interproximal_max_deg", r->angle_interproximal_min_deg,
            r->angle_interproximal_max_deg);
    const double weights = r->weight_depth + r->weight_force + r->weight_angulation + r->weight_walking +
                           r->weight_withdrawals + r->weight_completeness + r->weight_time;
    if (!(weights > 0.0)) f.add(path, "the weights are all zero (at least one row must count)");
}

// ---- the case's chart -----------------------------------------------------------------------

// `inner` lies in (or is) `outer`: both absolute and normalized.
bool is_within(const fs::path& inner, const fs::path& outer) {
    auto i = inner.begin();
    for (auto o = outer.begin(); o != outer.end(); ++o) {
        if (o->empty()) continue;  // a trailing separator
        if (i == inner.end() || *i != *o) return false;
        ++i;
    }
    return true;
}

fs::path canonical_or_lexical(const fs::path& p) {
    std::error_code ec;
    fs::path abs = fs::absolute(p, ec);
    if (ec) abs = p;
    fs::path c = fs::weakly_canonical(abs, ec);
    return (ec ? abs.lexically_normal() : c);
}

// Resolves the chart inside the content root, loads it; the chart's teeth (ascending), or nothing
// when it could not be read.
std::optional<std::vector<int>> read_case_chart(const Faults& f, const std::string& chart,
                                                const std::string& content_root, std::string* chart_path) {
    const std::string here = "case.chart";
    if (fs::path(chart).is_absolute()) {
        f.add(here, quote_text(chart) + " is an absolute path (write it relative to the content root)");
        return std::nullopt;
    }
    const fs::path root = canonical_or_lexical(content_root);
    const fs::path target = canonical_or_lexical(root / chart);
    if (!is_within(target, root)) {
        f.add(here, quote_text(chart) + " is outside the content root " + root.string());
        return std::nullopt;
    }
    std::error_code ec;
    if (!fs::is_regular_file(target, ec)) {
        f.add(here, quote_text(chart) + " is not a file in the content root (looked for " + target.string() + ")");
        return std::nullopt;
    }
    *chart_path = target.string();
    const ChartLoad load = load_chart(target.string());
    f.out->insert(f.out->end(), load.errors.begin(), load.errors.end());
    if (!load.ok()) return std::nullopt;
    std::vector<int> teeth;
    for (const auto& [fdi, tooth] : load.chart.teeth) teeth.push_back(fdi);
    return teeth;
}

// ---- the text -------------------------------------------------------------------------------

std::pair<std::size_t, std::size_t> line_column(const std::string& text, std::size_t byte) {
    byte = std::min(byte, text.size());
    std::size_t line = 1, column = 1;
    for (std::size_t i = 0; i < byte; ++i) {
        if (text[i] == '\n') {
            ++line;
            column = 1;
        } else if ((static_cast<unsigned char>(text[i]) & 0xC0) != 0x80) {
            ++column;
        }
    }
    return {line, column};
}

// Scans the nesting of arrays and objects outside strings before the JSON parser (which recurses)
// sees the text. Returns false, with a fault, at the first bracket past the limit.
bool check_depth(const Faults& f, const std::string& text) {
    std::size_t depth = 0;
    bool in_string = false, escaped = false;
    for (std::size_t i = 0; i < text.size(); ++i) {
        const char c = text[i];
        if (in_string) {
            if (escaped) escaped = false;
            else if (c == '\\') escaped = true;
            else if (c == '"') in_string = false;
            continue;
        }
        if (c == '"') in_string = true;
        else if (c == ']' || c == '}') depth = depth > 0 ? depth - 1 : 0;
        else if ((c == '[' || c == '{') && ++depth > kMaxLessonDepth) {
            const auto [line, column] = line_column(text, i);
            f.add("", "line " + std::to_string(line) + ", column " + std::to_string(column) + " (byte " +
                          std::to_string(i + 1) + "): arrays and objects nested deeper than the " +
                          std::to_string(kMaxLessonDepth) + " levels allowed");
            return false;
        }
    }
    return true;
}

// The parser quotes what it last read, which may be a broken UTF-8 sequence: keep messages ASCII.
std::string ascii(std::string s) {
    for (char& c : s)
        if (static_cast<unsigned char>(c) >= 0x80) c = '?';
    return s;
}

// Parses, reporting a syntax error by line and column, and keys written twice in one object (the
// parser would keep the last silently) by their JSON path.
bool parse_text(const Faults& f, const std::string& text, json* doc) {
    struct Frame {
        bool object;
        std::string path;
        std::string key;
        std::size_t count = 0;
        std::set<std::string> keys;
    };
    std::vector<Frame> stack;
    const auto element_path = [&]() -> std::string {
        if (stack.empty()) return "";
        Frame& top = stack.back();
        if (top.object) return key_path(top.path, top.key);
        return index_path(top.path, top.count++);
    };
    const json::parser_callback_t cb = [&](int, json::parse_event_t event, json& parsed) {
        switch (event) {
            case json::parse_event_t::object_start:
            case json::parse_event_t::array_start: {
                std::string p = element_path();
                stack.push_back(Frame{event == json::parse_event_t::object_start, p, "", 0, {}});
                break;
            }
            case json::parse_event_t::object_end:
            case json::parse_event_t::array_end:
                if (!stack.empty()) stack.pop_back();
                break;
            case json::parse_event_t::key:
                if (!stack.empty()) {
                    Frame& top = stack.back();
                    top.key = parsed.get<std::string>();
                    if (!top.keys.insert(top.key).second)
                        f.add(key_path(top.path, top.key), "written twice in one object");
                }
                break;
            case json::parse_event_t::value:
                if (!stack.empty() && !stack.back().object) ++stack.back().count;
                break;
        }
        return true;
    };
    try {
        *doc = json::parse(text, cb);
        return true;
    } catch (const json::parse_error& e) {
        const auto [line, column] = line_column(text, e.byte > 0 ? e.byte - 1 : 0);
        std::string what = e.what();
        // nlohmann: "[json.exception.parse_error.101] parse error at line L, column C: what"
        if (const auto c = what.find("column "); c != std::string::npos)
            if (const auto colon = what.find(": ", c); colon != std::string::npos) what = what.substr(colon + 2);
        f.add("", "line " + std::to_string(line) + ", column " + std::to_string(column) + ": " + ascii(what));
        return false;
    } catch (const json::exception& e) {
        // e.g. a number too large for a double: "[json.exception.out_of_range.406] number overflow ..."
        std::string what = e.what();
        if (const auto b = what.find("] "); b != std::string::npos) what = what.substr(b + 2);
        f.add("", "not valid JSON: " + ascii(what));
        return false;
    }
}

std::string default_root(const std::string& source) {
    std::error_code ec;
    fs::path p = fs::absolute(source, ec);
    if (ec) p = source;
    return p.parent_path().parent_path().string();
}

}  // namespace

// ---- public ---------------------------------------------------------------------------------

const char* step_order_name(StepOrder o) {
    switch (o) {
        case StepOrder::Any: return "any";
        case StepOrder::Listed: return "listed";
    }
    return "?";
}
const char* step_condition_name(StepCondition c) {
    switch (c) {
        case StepCondition::Charted: return "charted";
        case StepCondition::Probed: return "probed";
        case StepCondition::Walked: return "walked";
        case StepCondition::Acknowledged: return "acknowledged";
    }
    return "?";
}
const char* rule_trigger_name(RuleTrigger t) {
    switch (t) {
        case RuleTrigger::ForceAbove: return "force_above";
        case RuleTrigger::ForceAtLeast: return "force_at_least";
        case RuleTrigger::LeftSulcus: return "left_sulcus";
    }
    return "?";
}
const char* rule_level_name(RuleLevel l) {
    switch (l) {
        case RuleLevel::Note: return "note";
        case RuleLevel::Warning: return "warning";
    }
    return "?";
}

bool parse_site_ref(const std::string& text, SiteRef* out) {
    if (text.size() < 3 || text[0] < '1' || text[0] > '4' || text[1] < '1' || text[1] > '8') return false;
    Site site;
    if (!parse_site(text.substr(2), &site)) return false;
    if (out) *out = SiteRef{(text[0] - '0') * 10 + (text[1] - '0'), site};
    return true;
}

std::string site_ref_name(const SiteRef& ref) { return std::to_string(ref.fdi) + site_name(ref.site); }

std::vector<SiteRef> Lesson::target_sites() const {
    std::vector<SiteRef> out;
    for (const LessonStep& s : steps)
        for (const SiteRef& r : s.sites)
            if (std::find(out.begin(), out.end(), r) == out.end()) out.push_back(r);
    return out;
}

LessonLoad load_lesson(const std::string& path, const std::string& content_root) {
    const std::string root = content_root.empty() ? default_root(path) : content_root;
    LessonLoad result;
    result.source = path;
    std::error_code ec;
    const fs::file_status st = fs::status(path, ec);
    if (ec || !fs::exists(st)) {
        result.errors.push_back(one_line(path + ": no such file"));
        return result;
    }
    if (fs::is_directory(st)) {
        result.errors.push_back(one_line(path + ": is a folder, not a lesson file"));
        return result;
    }
    const std::uintmax_t size = fs::is_regular_file(st) ? fs::file_size(path, ec) : 0;
    const auto too_big = [&](std::uintmax_t n) {
        result.errors.push_back(one_line(path + ": " + std::to_string(n) + " bytes, larger than the " +
                                         std::to_string(kMaxLessonBytes) + " allowed for a lesson"));
        return result;
    };
    if (!ec && size > kMaxLessonBytes) return too_big(size);
    std::ifstream in(path, std::ios::binary);
    if (!in) {
        result.errors.push_back(one_line(path + ": cannot be read"));
        return result;
    }
    // Read at most one byte past the limit: the file may have grown, or not be a regular file.
    std::string text(kMaxLessonBytes + 1, '\0');
    in.read(text.data(), std::streamsize(text.size()));
    text.resize(std::size_t(in.gcount()));
    if (in.bad()) {
        result.errors.push_back(one_line(path + ": cannot be read"));
        return result;
    }
    if (text.size() > kMaxLessonBytes) return too_big(std::max<std::uintmax_t>(size, text.size()));
    return parse_lesson(text, path, root);
}

LessonLoad parse_lesson(const std::string& text, const std::string& source, const std::string& content_root) {
    LessonLoad result;
    result.source = source;
    const Faults f{source, &result.errors};
    if (text.size() > kMaxLessonBytes) {
        f.add("", std::to_string(text.size()) + " bytes, larger than the " + std::to_string(kMaxLessonBytes) +
                      " allowed for a lesson");
        return result;
    }
    if (!check_depth(f, text)) return result;
    json doc;
    if (!parse_text(f, text, &doc)) return result;
    if (!doc.is_object()) {
        f.add("", "expected a JSON object at the top level, found " + found(doc));
        return result;
    }
    Lesson& l = result.lesson;
    l.format.clear();
    check_keys(f, doc, "", {"format", "title", "description", "case", "probe", "steps", "rules", "rubric"});

    if (const json* v = member(doc, "format"); !v)
        f.add("format", std::string("missing (expected \"") + kLessonFormat + "\")");
    else if (!v->is_string() || v->get_ref<const std::string&>() != kLessonFormat)
        f.add("format", std::string("expected \"") + kLessonFormat + "\", found " + found(*v));
    else
        l.format = kLessonFormat;
    read_string(f, doc, "title", "", true, false, &l.title);
    read_string(f, doc, "description", "", false, true, &l.description);

    std::string name;
    if (read_string(f, doc, "probe", "", false, true, &name) && !parse_probe_kind(name, &l.probe))
        f.add("probe", "unknown probe " + quote_text(name) +
                           " (expected \"williams\", \"unc15\", \"cpi\", \"marquis\" or \"nabers\")");

    // The case: the chart and the teeth.
    std::optional<std::vector<int>> chart_teeth;
    bool teeth_listed = false;
    if (const json* c = member(doc, "case"); !c) {
        f.add("case", "missing (an object with the \"chart\" the lesson runs on)");
    } else if (!c->is_object()) {
        f.add("case", "expected an object, found " + found(*c));
    } else {
        check_keys(f, *c, "case", {"chart", "teeth"});
        if (const json* a = read_array(f, *c, "teeth", "case", 32, "teeth")) {
            teeth_listed = true;
            for (std::size_t i = 0; i < a->size(); ++i) {
                const std::string here = index_path("case.teeth", i);
                std::int64_t n = 0;
                if (!as_integer((*a)[i], &n) || !valid_fdi(n)) {
                    f.add(here, "expected an FDI tooth number (11-48), found " + found((*a)[i]));
                    continue;
                }
                if (std::find(l.teeth.begin(), l.teeth.end(), int(n)) != l.teeth.end()) {
                    f.add(here, "tooth " + std::to_string(n) + " is listed twice");
                    continue;
                }
                l.teeth.push_back(int(n));
            }
        } else if (member(*c, "teeth")) {
            teeth_listed = true;  // faulty: reported; do not fill in the chart's teeth
        }
        if (read_string(f, *c, "chart", "case", true, false, &l.chart))
            chart_teeth = read_case_chart(f, l.chart, content_root.empty() ? default_root(source) : content_root,
                                          &result.chart_path);
    }
    if (chart_teeth) {
        if (teeth_listed) {
            std::string have;
            for (int t : *chart_teeth) have += (have.empty() ? "" : ", ") + std::to_string(t);
            for (std::size_t i = 0; i < l.teeth.size(); ++i)
                if (std::find(chart_teeth->begin(), chart_teeth->end(), l.teeth[i]) == chart_teeth->end())
                    f.add(index_path("case.teeth", i), "tooth " + std::to_string(l.teeth[i]) + " is not in the chart " +
                                                           quote_text(l.chart) + " (it has " + have + ")");
        } else {
            l.teeth = *chart_teeth;
        }
    }
    // Sites can be checked against the teeth once the teeth are known.
    const bool teeth_known = teeth_listed || chart_teeth.has_value();

    // Steps.
    if (const json* a = member(doc, "steps"); !a) {
        f.add("steps", "missing (a lesson needs at least one step)");
    } else if (const json* s = read_array(f, doc, "steps", "", kMaxLessonSteps, "steps")) {
        if (s->empty()) f.add("steps", "empty (a lesson needs at least one step)");
        std::set<std::string> ids;
        for (std::size_t i = 0; i < s->size(); ++i) {
            const std::string here = index_path("steps", i);
            LessonStep step;
            read_step(f, (*s)[i], here, teeth_known ? &l.teeth : nullptr, &step);
            if (!step.id.empty() && !ids.insert(step.id).second)
                f.add(key_path(here, "id"), quote_text(step.id) + " is the id of an earlier step (ids must be unique)");
            l.steps.push_back(std::move(step));
        }
    }

    // Rules.
    if (const json* a = read_array(f, doc, "rules", "", kMaxLessonRules, "rules")) {
        std::set<std::string> ids;
        for (std::size_t i = 0; i < a->size(); ++i) {
            const std::string here = index_path("rules", i);
            LessonRule rule;
            read_rule(f, (*a)[i], here, &rule);
            if (!rule.id.empty() && !ids.insert(rule.id).second)
                f.add(key_path(here, "id"), quote_text(rule.id) + " is the id of an earlier rule (ids must be unique)");
            l.rules.push_back(std::move(rule));
        }
    }

    if (const json* r = member(doc, "rubric")) read_rubric(f, *r, "rubric", &l.rubric);
    return result;
}

json lesson_to_json(const Lesson& l) {
    json doc = json::object();
    doc["format"] = l.format;
    doc["title"] = l.title;
    doc["description"] = l.description;
    doc["case"] = {{"chart", l.chart}, {"teeth", l.teeth}};
    doc["probe"] = probe_kind_name(l.probe);
    json steps = json::array();
    for (const LessonStep& s : l.steps) {
        json sites = json::array();
        for (const SiteRef& r : s.sites) sites.push_back(site_ref_name(r));
        json hints = json::array();
        for (const LessonHint& h : s.hints) hints.push_back({{"text", h.text}, {"after_s", h.after_s}});
        steps.push_back({{"id", s.id},
                         {"instruction", s.instruction},
                         {"sites", sites},
                         {"order", step_order_name(s.order)},
                         {"complete", step_condition_name(s.complete)},
                         {"hints", hints}});
    }
    doc["steps"] = steps;
    json rules = json::array();
    for (const LessonRule& r : l.rules) {
        json j = {{"id", r.id}, {"when", rule_trigger_name(r.when)}};
        if (r.when != RuleTrigger::LeftSulcus) j["threshold_N"] = r.threshold_N;
        j["level"] = rule_level_name(r.level);
        j["message"] = r.message;
        j["cooldown_s"] = r.cooldown_s;
        rules.push_back(j);
    }
    doc["rules"] = rules;
    json rubric = json::object();
    for (const RubricField& fld : kRubricFields) rubric[fld.name] = l.rubric.*fld.member;
    rubric[kWithdrawalsKey] = l.rubric.max_withdrawals_per_side;
    doc["rubric"] = rubric;
    return doc;
}

}  // namespace sulcus

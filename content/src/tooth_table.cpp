// The anatomy table of the permanent teeth, tooth numbering and probing-site names.
//
// Crown and root lengths, crown and cervical diameters and the curvature of the cervical line are
// the "measurements of the teeth" table of Wheeler's Dental Anatomy, Physiology and Occlusion
// (Nelson & Ash), in millimetres. Root counts are the usual ones; root trunk lengths (CEJ to the
// furcation entrance on the buccal side) are typical values from periodontology texts (Carranza's
// Clinical Periodontology). docs/anatomy.md says which rows were checked against an excerpt.
#include "sulcus/content/tooth.h"

#include <stdexcept>

namespace sulcus {

namespace {

struct Row {
    ToothClass cls;
    double crown, root, md, md_cervix, bl, bl_cervix, cej_m, cej_d;
    int roots;
    double trunk;
};

// Position 1-7 from the midline; root length is that of the longest root (the palatal root of
// the upper molars, the buccal root of the upper first premolar, the mesial root of lower molars).
constexpr Row kUpper[7] = {
    {ToothClass::CentralIncisor, 10.5, 13.0, 8.5, 7.0, 7.0, 6.0, 3.5, 2.5, 1, 0.0},
    {ToothClass::LateralIncisor, 9.0, 13.0, 6.5, 5.0, 6.0, 5.0, 3.0, 2.0, 1, 0.0},
    {ToothClass::Canine, 10.0, 17.0, 7.5, 5.5, 8.0, 7.0, 2.5, 1.5, 1, 0.0},
    {ToothClass::FirstPremolar, 8.5, 14.0, 7.0, 5.0, 9.0, 8.0, 1.0, 0.0, 2, 8.0},
    {ToothClass::SecondPremolar, 8.5, 14.0, 7.0, 5.0, 9.0, 8.0, 1.0, 0.0, 1, 0.0},
    {ToothClass::FirstMolar, 7.5, 13.0, 10.0, 8.0, 11.0, 10.0, 1.0, 0.0, 3, 4.0},
    {ToothClass::SecondMolar, 7.0, 12.0, 9.0, 7.0, 11.0, 10.0, 1.0, 0.0, 3, 4.0},
};
constexpr Row kLower[7] = {
    {ToothClass::CentralIncisor, 9.0, 12.5, 5.0, 3.5, 6.0, 5.3, 3.0, 2.0, 1, 0.0},
    {ToothClass::LateralIncisor, 9.5, 14.0, 5.5, 4.0, 6.5, 5.8, 3.0, 2.0, 1, 0.0},
    {ToothClass::Canine, 11.0, 16.0, 7.0, 5.5, 7.5, 7.0, 2.5, 1.0, 1, 0.0},
    {ToothClass::FirstPremolar, 8.5, 14.0, 7.0, 5.0, 7.5, 6.5, 1.0, 0.0, 1, 0.0},
    {ToothClass::SecondPremolar, 8.0, 14.5, 7.0, 5.0, 8.0, 7.0, 1.0, 0.0, 1, 0.0},
    {ToothClass::FirstMolar, 7.5, 14.0, 11.0, 9.0, 10.5, 9.0, 1.0, 0.0, 2, 3.0},
    {ToothClass::SecondMolar, 7.0, 13.0, 10.5, 8.0, 10.0, 9.0, 1.0, 0.0, 2, 4.0},
};

// All 28 rows, built once (left and right share the numbers of their row).
struct Table {
    ToothDimensions rows[4][7];
    Table() {
        for (int q = 1; q <= 4; ++q)
            for (int i = 1; i <= 7; ++i) {
                const Row& r = (q <= 2 ? kUpper : kLower)[i - 1];
                ToothDimensions& d = rows[q - 1][i - 1];
                d.fdi = q * 10 + i;
                d.cls = r.cls;
                d.upper = q <= 2;
                d.crown_length_mm = r.crown;
                d.root_length_mm = r.root;
                d.crown_md_mm = r.md;
                d.cervix_md_mm = r.md_cervix;
                d.crown_bl_mm = r.bl;
                d.cervix_bl_mm = r.bl_cervix;
                d.cej_curve_mesial_mm = r.cej_m;
                d.cej_curve_distal_mm = r.cej_d;
                d.roots = r.roots;
                d.trunk_length_mm = r.trunk;
            }
    }
};

const Table& table() {
    static const Table t;
    return t;
}

}  // namespace

bool is_supported_tooth(int fdi) {
    const int q = fdi / 10, i = fdi % 10;
    return q >= 1 && q <= 4 && i >= 1 && i <= 7;
}

std::vector<int> supported_teeth() {
    std::vector<int> out;
    for (int q = 1; q <= 4; ++q)
        for (int i = 1; i <= 7; ++i) out.push_back(q * 10 + i);
    return out;
}

const ToothDimensions& tooth_dimensions(int fdi) {
    if (!is_supported_tooth(fdi))
        throw std::invalid_argument("tooth " + std::to_string(fdi) +
                                    ": not a supported FDI number (11-17, 21-27, 31-37, 41-47)");
    return table().rows[fdi / 10 - 1][fdi % 10 - 1];
}

int universal_number(int fdi) {
    const int q = fdi / 10, i = fdi % 10;
    if (i < 1 || i > 8) return 0;
    switch (q) {
        case 1: return 9 - i;   // upper right: 18 -> 1 ... 11 -> 8
        case 2: return 8 + i;   // upper left: 21 -> 9 ... 28 -> 16
        case 3: return 25 - i;  // lower left: 38 -> 17 ... 31 -> 24
        case 4: return 24 + i;  // lower right: 41 -> 25 ... 48 -> 32
        default: return 0;
    }
}

const char* site_name(Site s) {
    switch (s) {
        case Site::MB: return "MB";
        case Site::B: return "B";
        case Site::DB: return "DB";
        case Site::ML: return "ML";
        case Site::L: return "L";
        case Site::DL: return "DL";
    }
    return "?";
}

bool parse_site(const std::string& name, Site* out) {
    for (Site s : kAllSites)
        if (name == site_name(s)) {
            if (out) *out = s;
            return true;
        }
    return false;
}

}  // namespace sulcus

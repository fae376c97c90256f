#pragma once
// summary.html: the class at a glance, for staff. A self-contained page that opens from disk (no
// scripts, no network): per task and for the totals the mean and median points, the distribution
// of totals as a histogram picture (summary-totals.png beside the page, drawn here: bars and tick
// marks only, its labels are HTML around it), and per task the students who lost most (the 5
// lowest below full points, with their points and reason), each linked to their feedback page
// (feedback/<folder>/index.html, as write_feedback_pages lays it out in the same folder).
#include <filesystem>
#include <vector>

#include "renderer/compare/image.h"
#include "server/grade/grade_outcome.h"

namespace farm {

// The histogram: kHistogramBins bars, bar i counting the totals in [i, i+1) tenths of the maximum
// (the last bar includes the maximum), on a white picture with black axes, a tick below the x axis
// at every bar edge and one left of the y axis (with a light grey grid line) every `step` students.
inline constexpr int kHistogramBins = 10;
inline constexpr int kHistogramWidth = 480, kHistogramHeight = 240;
inline constexpr float kHistogramBar[3] = {41.0f / 255.0f, 98.0f / 255.0f, 171.0f / 255.0f};

// How many totals fall in each of the kHistogramBins bins of [0, maximum].
std::vector<int> total_histogram(const ClassGrades& grades);

// The histogram of `counts` as an R G B picture (display values), kHistogramWidth x
// kHistogramHeight; `step` is the y tick spacing in students.
Image draw_histogram(const std::vector<int>& counts, int step);

// The median of `values` (the mean of the middle two for an even count); 0 when empty.
double median_of(std::vector<double> values);

// Writes <dir>/summary.html and <dir>/summary-totals.png; returns the page's path.
std::filesystem::path write_class_summary(const ClassGrades& grades, const std::filesystem::path& dir);

}  // namespace farm

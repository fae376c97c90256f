#pragma once
// similar.csv: pairs of students whose images for the same file task are identical or nearly so,
// for staff to look at. It only points; it never changes a score.
//
//   task,student_a,student_b,flip_mean,identical
//
// For every file task (a rubric task with `file`; without a rubric, every task), the
// TaskGrade::student_png of every pair of students (none: skipped) are compared, as display values
// (to_display), in steps that bound the work. N students make N^2/2 pairs, and LDR-FLIP at
// 640x480 costs ~0.045 s: 100 students would be 4950 runs, nearly 4 minutes on one core, for
// every task. So FLIP only judges pairs that two cheap tests could not tell apart:
//   1. Each image is decoded once and reduced to a signature: SHA-256 of its size and pixel
//      values, and a 16 x 16 thumbnail (box means of R G B). Equal hashes: identical (flip_mean 0,
//      identical 1), no FLIP run. Images of different sizes are never alike.
//   2. Thumbnail: the mean absolute difference of the thumbnails' values must be at most
//      `thumbnail_tolerance` (microseconds a pair). It sees differences over large areas (a
//      shift of brightness or colour, a repainted region), which FLIP (whose filters pass low
//      frequencies) scores far above the threshold: a brightness shift of 0.03 alone gives FLIP
//      means of 0.1 to 0.2.
//   3. Pixels: the mean absolute difference of the full-size pixels must be at most
//      `pixel_tolerance` (about a millisecond at 640x480). It sees what the thumbnail averages
//      out: noise, which makes the common case of a class whose images all look alike at 16 x 16
//      (everyone rendered the same scene; path-traced noise differs) cheap. FLIP never scores a
//      difference much below its mean: the least it gives, for a checkerboard at the highest
//      frequency (which its spatial filters damp most), is about 0.58 x the mean.
//   4. LDR-FLIP (flip.h, flip_ldr, the student with the smaller id as reference) on the pairs
//      left: a mean below `flip_threshold` (0.01: a few changed pixels or a barely visible tint;
//      independent renders differ by more: Gaussian noise of sigma 1/255 alone scores ~0.02)
//      lists the pair.
// The thumbnail tolerance is 3 x the threshold; the pixel tolerance 2 x, the most FLIP's lower
// bound allows (FLIP >= 0.5 x the pixel distance): at 3 x, a class whose renders differ only by
// noise of sigma 0.02 (pixel distance ~0.023, FLIP ~0.05) sent every pair to FLIP, 900 runs and
// 140 s for 100 students and 3 tasks (farm bench grade). tests/unit/similar_submissions_test.cpp checks, over
// shifts, ramps, repainted blocks and noise of three kinds on bright and dark pictures, that every
// difference either prefilter rejects has a FLIP mean above the threshold, FLIP being at least
// 2 x the thumbnail distance and 0.5 x the pixel distance: margins of 6 and 1.5 over the
// threshold for the thumbnail, 1.16 for the pixels (the least ratio measured, 0.58, for a checkerboard
// difference, which renders hardly differ by; Gaussian noise scores 2 x its mean difference and
// more). What is left for FLIP is pairs alike at every scale: in a class, few. Two renders of one
// scene with independent noise of sigma 0.018 or more (a path tracer's at moderate sample counts)
// differ by more than the pixel tolerance; with less noise than that every such pair still goes
// to FLIP, at ~0.045 s each (a pool shares each run).
// Memory: the pixels of the students in pairs that pass step 2, at one byte a channel (100
// students at 640x480: 92 MB).
// An image identical to the task's reference (its TaskGrade::reference_png, by the same hash) is
// left out when `skip_reference_matches`: every student who renders the scene exactly right
// matches every other one, which says nothing about copying. Unreadable images are skipped.
// Pairs are listed per task in rubric order, most similar first, then by ids.
#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "renderer/compare/image.h"
#include "server/grade/grade_outcome.h"

namespace farm {

class ThreadPool;

struct SimilarityOptions {
  double flip_threshold = 0.01;
  double thumbnail_tolerance = 0.03;
  double pixel_tolerance = 0.02;
  bool skip_reference_matches = true;
  ThreadPool* pool = nullptr;  // for FLIP; null: the calling thread alone
};

struct SimilarPair {
  std::string task, student_a, student_b;  // student_a < student_b
  double flip_mean = 0.0;                  // 0 when identical
  bool identical = false;
};

// The prefilters' distances for two images of the same size (display values, as to_display gives
// them): the mean absolute difference of the 16 x 16 thumbnails' values, and of the pixels' R G B
// values. Exposed for tests.
double thumbnail_distance(const Image& a, const Image& b);
double pixel_distance(const Image& a, const Image& b);

// How much work each step did, over all tasks (for a log line, and for tests of the bound).
struct SimilarityCounts {
  std::size_t images = 0;     // signatures made
  std::size_t pairs = 0;      // pairs of images of one size
  std::size_t identical = 0;  // equal hashes
  std::size_t thumbnail = 0;  // pairs that passed the thumbnail
  std::size_t flip = 0;       // pairs that passed the pixels: FLIP runs
};

std::vector<SimilarPair> find_similar_submissions(const ClassGrades& grades, const SimilarityOptions& options = {},
                                                  SimilarityCounts* counts = nullptr);

// The table as text (csv_field.h quoting, CRLF).
std::string similar_csv(const std::vector<SimilarPair>& pairs);

// Writes <dir>/similar.csv atomically (the header alone when nothing is alike); returns the pairs.
std::vector<SimilarPair> write_similar_submissions(const ClassGrades& grades, const std::filesystem::path& dir,
                                                   const SimilarityOptions& options = {},
                                                   SimilarityCounts* counts = nullptr);

}  // namespace farm

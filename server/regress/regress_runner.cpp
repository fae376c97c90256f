#include "server/regress/regress_runner.h"

#include <fmt/format.h>
#include <fnmatch.h>

#include <atomic>
#include <chrono>
#include <map>
#include <mutex>
#include <thread>

#include "renderer/compare/image.h"
#include "renderer/util/atomic_file.h"
#include "renderer/image/preview.h"
#include "renderer/util/input_error.h"
#include "server/client/job_submission.h"
#include "server/client/scheduler_client.h"
#include "server/common/job_state.h"
#include "server/common/service_error.h"
#include "server/embedded/job_renderer.h"

namespace farm {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

// Where one test's files go: the new EXR and preview it renders, and the report's pictures.
struct TestFiles {
  fs::path exr, preview, reference_png, new_png, difference_png;
};

TestFiles files_of(const RegressTest& test, const fs::path& output_dir) {
  const fs::path images = output_dir / "images";
  return {images / (test.name + ".new.exr"), images / (test.name + ".new.png"), images / (test.name + ".ref.png"),
          images / (test.name + ".new-display.png"), images / (test.name + ".diff.png")};
}

JobSubmission submission_of(const RegressSuite& suite, const RegressTest& test, const TestFiles& files) {
  RenderOverrides overrides = test.render;
  overrides.image = files.exr;
  overrides.preview = files.preview;
  if (test.compare.metric == Metric::ztest) overrides.add_aovs.push_back("variance");  // the z-test's input
  JobLoadOptions load;
  load.asset_root = suite.asset_root;
  return make_job_submission(test.job, load, overrides);
}

TestOutcome error_outcome(const RegressTest& test, std::string message, Clock::time_point start) {
  TestOutcome out;
  out.name = test.name;
  out.settings = test.compare;
  out.status = TestStatus::error;
  out.message = std::move(message);
  out.reference = test.reference;
  out.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  return out;
}

// Copies `from` over `to` through a temporary file beside it: a reader never sees half a file.
void replace_atomically(const fs::path& from, const fs::path& to) {
  write_file_atomically(to, [&](const fs::path& temp) { fs::copy_file(from, temp, fs::copy_options::overwrite_existing); });
}

// Compares a rendered test with its reference and writes the report's pictures; updates the
// reference when asked. Never throws: a failure to read or write is the test's error.
TestOutcome judge(const RegressTest& test, const TestFiles& files, const RegressOptions& options, Clock::time_point start) {
  TestOutcome out;
  out.name = test.name;
  out.settings = test.compare;
  out.reference = test.reference;
  // An 8-bit reference (PNG or JPEG, by the names previews take) is compared with the new
  // preview, an EXR with the EXR.
  out.new_image = preview_format_supported(test.reference) ? files.preview : files.exr;
  try {
    const Image fresh = read_image(out.new_image);
    write_png_image(to_display(fresh), files.new_png);
    out.new_png = files.new_png;
    std::error_code ec;
    if (!fs::exists(test.reference, ec)) {
      out.reference_missing = true;
      out.status = TestStatus::failed;
      out.message = fmt::format("no reference at {}: run `farm regress SUITE --update` to create it from this render",
                                test.reference.string());
    } else {
      const Image reference = read_image(test.reference);
      write_png_image(to_display(reference), files.reference_png);
      out.reference_png = files.reference_png;
      out.result = compare_images(reference, fresh, test.compare);
      out.message = out.result.summary;
      out.status = out.result.verdict == Verdict::pass   ? TestStatus::passed
                   : out.result.verdict == Verdict::warn ? TestStatus::warned
                                                         : TestStatus::failed;
      if (out.result.difference.pixel_count() > 0) {
        write_png_image(out.result.difference, files.difference_png);
        out.difference_png = files.difference_png;
      }
    }
    const bool update = options.update == ReferenceUpdate::all ||
                        (options.update == ReferenceUpdate::failed && out.status == TestStatus::failed);
    if (update) {
      replace_atomically(out.new_image, test.reference);
      out.reference_updated = true;
    }
  } catch (const std::exception& e) {
    out.status = TestStatus::error;
    out.message = e.what();
  }
  out.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  return out;
}

// Reports outcomes one at a time and keeps them in suite order.
class Collector {
 public:
  Collector(std::vector<TestOutcome>& outcomes, const RegressEvents& events, std::size_t total)
      : outcomes_(outcomes), events_(events), total_(total) {}
  void add(std::size_t index, TestOutcome outcome) {
    std::lock_guard lock(mutex_);
    outcomes_[index] = std::move(outcome);
    if (events_.finished) events_.finished(outcomes_[index]);
    if (events_.progress) events_.progress(++done_, total_);
  }

 private:
  std::mutex mutex_;
  std::vector<TestOutcome>& outcomes_;
  const RegressEvents& events_;
  std::size_t total_, done_ = 0;
};

void run_embedded(const RegressSuite& suite, const std::vector<std::size_t>& selected, const RegressOptions& options,
                  Collector& collector) {
  JobRenderer renderer(std::nullopt, options.threads);
  std::atomic<std::size_t> next{0};
  const auto work = [&] {
    for (std::size_t i; (i = next++) < selected.size();) {
      const RegressTest& test = suite.tests[selected[i]];
      const auto start = Clock::now();
      const TestFiles files = files_of(test, options.output_dir);
      try {
        renderer.render(submission_of(suite, test, files), files.exr, files.preview);
      } catch (const std::exception& e) {
        collector.add(selected[i], error_outcome(test, e.what(), start));
        continue;
      }
      collector.add(selected[i], judge(test, files, options, start));
    }
  };
  std::vector<std::thread> threads;
  const int jobs = std::max(1, std::min<int>(options.jobs, static_cast<int>(selected.size())));
  for (int t = 1; t < jobs; ++t) threads.emplace_back(work);
  work();
  for (std::thread& t : threads) t.join();
}

void run_on_scheduler(const RegressSuite& suite, const std::vector<std::size_t>& selected,
                      const RegressOptions& options, Collector& collector) {
  SchedulerClient client(*options.scheduler);
  struct Pending {
    std::size_t index;
    TestFiles files;
    Clock::time_point start;
  };
  std::map<std::string, Pending> pending;  // by job id
  // Everything is submitted first, so the farm renders the suite in parallel across its workers.
  for (std::size_t index : selected) {
    const RegressTest& test = suite.tests[index];
    const auto start = Clock::now();
    const TestFiles files = files_of(test, options.output_dir);
    try {
      const JobSubmission submission = submission_of(suite, test, files);
      client.upload_missing(submission);
      const v1::Job job = client.submit(submission, 0);
      pending.emplace(job.job_id(), Pending{index, files, start});
    } catch (const ServiceError&) {
      throw;  // the scheduler is unreachable: nothing else will go better
    } catch (const std::exception& e) {
      collector.add(index, error_outcome(test, e.what(), start));
    }
  }
  // Then results are compared as they arrive.
  while (!pending.empty()) {
    bool any = false;
    for (auto it = pending.begin(); it != pending.end();) {
      const v1::Job job = client.get(it->first);
      if (!is_final(job.state())) {
        ++it;
        continue;
      }
      any = true;
      const RegressTest& test = suite.tests[it->second.index];
      if (job.state() != v1::JOB_STATE_SUCCEEDED) {
        collector.add(it->second.index, error_outcome(test, fmt::format("the render {}: {}", to_string(job.state()),
                                                                        job.failure_reason()), it->second.start));
      } else {
        try {
          client.fetch(job.job_id(), v1::RESULT_KIND_EXR, [&](const std::string&) { return it->second.files.exr; });
          client.fetch(job.job_id(), v1::RESULT_KIND_PREVIEW, [&](const std::string&) { return it->second.files.preview; });
          collector.add(it->second.index, judge(test, it->second.files, options, it->second.start));
        } catch (const std::exception& e) {
          collector.add(it->second.index, error_outcome(test, e.what(), it->second.start));
        }
      }
      it = pending.erase(it);
    }
    if (!any) std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
}

}  // namespace

std::string_view to_string(TestStatus status) {
  switch (status) {
    case TestStatus::passed: return "PASS";
    case TestStatus::warned: return "WARN";
    case TestStatus::failed: return "FAIL";
    case TestStatus::error: return "ERROR";
    case TestStatus::skipped: return "SKIP";
  }
  return "?";
}

bool glob_matches(const std::string& pattern, const std::string& name) {
  return fnmatch(pattern.c_str(), name.c_str(), 0) == 0;
}

std::vector<TestOutcome> run_regress_suite(const RegressSuite& suite, const RegressOptions& options,
                                           const RegressEvents& events) {
  std::vector<TestOutcome> outcomes(suite.tests.size());
  std::vector<std::size_t> selected;
  for (std::size_t i = 0; i < suite.tests.size(); ++i) {
    const RegressTest& test = suite.tests[i];
    bool chosen = options.filters.empty();
    for (const std::string& pattern : options.filters) chosen = chosen || glob_matches(pattern, test.name);
    if (chosen) {
      selected.push_back(i);
    } else {
      outcomes[i].name = test.name;
      outcomes[i].settings = test.compare;
      outcomes[i].status = TestStatus::skipped;
      outcomes[i].reference = test.reference;
      outcomes[i].message = "not selected by --filter";
    }
  }
  fs::create_directories(options.output_dir / "images");
  Collector collector(outcomes, events, selected.size());
  if (options.scheduler) {
    run_on_scheduler(suite, selected, options, collector);
  } else {
    run_embedded(suite, selected, options, collector);
  }
  return outcomes;
}

}  // namespace farm

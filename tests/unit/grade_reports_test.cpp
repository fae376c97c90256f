// The grading reports (server/grade: grades_csv, feedback_pages, gradescope_results,
// class_summary, similar_submissions) over one class built by hand: a rubric of two file tasks
// (one visible, one after_published) and a run task (hidden), five students, two of them with
// hostile ids (a comma and a quote; <script>), one with <script> in its program's output; for
// the cow task alice and bob hand in identical images, carol the same with one pixel changed,
// dave a different one. The CSVs are read back by Python's csv module and the results.json files
// checked against Gradescope's specification by jsonschema (tests/python/validate_json_schema.py).
#include <gtest/gtest.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <string>
#include <vector>

#include "renderer/compare/image.h"
#include "server/common/markup_escape.h"
#include "server/grade/feedback_pages.h"
#include "server/grade/grade_points.h"
#include "server/grade/grades_csv.h"
#include "server/grade/gradescope_results.h"
#include "server/grade/similar_submissions.h"
#include "server/grade/student_folder.h"
#include "server/grade/class_summary.h"
#include "tests/support/run_command.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

const std::string kComma = "dave, \"the\" hacker";
const std::string kScript = "<script>alert(1)</script>";
const std::string kScriptOutput = "building...\n<script>alert('pwned')</script>\nsegfault & core dumped";

std::string bytes_of(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// A 32x24 picture: a gradient with a block whose place and colour depend on `seed`.
Image picture(int seed) {
  Image image = make_image(32, 24, {"R", "G", "B"});
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      image.at(x, y, 0) = static_cast<float>(x) / 31.0f;
      image.at(x, y, 1) = static_cast<float>(y) / 23.0f;
      image.at(x, y, 2) = 0.5f;
      if (x >= 4 + seed * 5 && x < 12 + seed * 5 && y >= 6 && y < 16) {
        image.at(x, y, 0) = 0.1f * static_cast<float>(seed);
        image.at(x, y, 1) = 1.0f - 0.2f * static_cast<float>(seed);
        image.at(x, y, 2) = 0.9f;
      }
    }
  return image;
}

Image solid(float r, float g, float b) {
  Image image = make_image(32, 24, {"R", "G", "B"});
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      image.at(x, y, 0) = r;
      image.at(x, y, 1) = g;
      image.at(x, y, 2) = b;
    }
  return image;
}

struct Spec {
  std::string student;
  double cow, teapot, program;
};

class GradeReportsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    rubric_.name = "Lab 3 <shading> & co";
    rubric_.file = dir_ / "rubric" / "rubric.json";
    rubric_.folder = dir_ / "rubric";
    GradeTask cow;
    cow.name = "cow";
    cow.points = 60;
    cow.file = "cow.png";
    GradeTask teapot;
    teapot.name = "teapot";
    teapot.points = 30;
    teapot.file = "teapot.png";
    teapot.visibility = Visibility::after_published;
    GradeTask program;
    program.name = "program";
    program.points = 10;
    program.run = RunSpec{};
    program.visibility = Visibility::hidden;
    rubric_.tasks = {cow, teapot, program};

    const fs::path images = dir_ / "runner";
    write_png_image(picture(0), images / "reference_cow.png");
    write_png_image(solid(0.2f, 0.3f, 0.4f), images / "reference_teapot.png");
    write_png_image(solid(1, 0, 0), images / "difference.png");
    write_png_image(picture(1), images / "alice_cow.png");
    write_png_image(picture(1), images / "bob_cow.png");  // the same pixels as alice's
    Image near = picture(1);
    near.at(20, 20, 0) += 0.3f;  // one pixel changed
    write_png_image(near, images / "carol_cow.png");
    write_png_image(picture(3), images / "dave_cow.png");
    write_png_image(solid(0.9f, 0.1f, 0.1f), images / "script_cow.png");
    // teapot: alice and dave hand in the reference itself (not listed as alike); the others differ.
    write_png_image(solid(0.2f, 0.3f, 0.4f), images / "alice_teapot.png");
    write_png_image(solid(0.2f, 0.3f, 0.4f), images / "dave_teapot.png");
    write_png_image(solid(0.9f, 0.9f, 0.1f), images / "bob_teapot.png");
    write_png_image(solid(0.1f, 0.9f, 0.9f), images / "carol_teapot.png");
    write_png_image(solid(0.5f, 0.1f, 0.8f), images / "script_teapot.png");

    const std::vector<Spec> specs = {{"alice", 60, 30, 10},
                                     {"bob", 37.5, 12.25, 0},
                                     {"carol", 45, 30, 5},
                                     {kComma, 0, 30, 10},
                                     {kScript, 20, 0, 0}};
    const std::map<std::string, std::string> file_stem = {
        {"alice", "alice"}, {"bob", "bob"}, {"carol", "carol"}, {kComma, "dave"}, {kScript, "script"}};
    for (const Spec& spec : specs) {
      StudentGrade s;
      s.student = spec.student;
      s.seconds = 3.25;
      const std::string stem = file_stem.at(spec.student);
      TaskGrade cow_grade;
      cow_grade.task = "cow";
      cow_grade.points = spec.cow;
      cow_grade.max_points = 60;
      cow_grade.reason = fmt::format("FLIP mean {}: 0.05 earns all 60 points, 0.25 none", 0.25 - spec.cow / 300);
      cow_grade.compared = true;
      cow_grade.result.metric = Metric::flip;
      cow_grade.result.figures = {{"flip_mean", 0.25 - spec.cow / 300}};
      cow_grade.student_png = images / (stem + "_cow.png");
      cow_grade.reference_png = images / "reference_cow.png";
      cow_grade.difference_png = images / "difference.png";
      TaskGrade teapot_grade;
      teapot_grade.task = "teapot";
      teapot_grade.points = spec.teapot;
      teapot_grade.max_points = 30;
      teapot_grade.visibility = Visibility::after_published;
      teapot_grade.reason = spec.teapot == 0 ? "teapot.png: expected <b>32x24</b>, got 800x600"
                                             : fmt::format("PSNR {} dB", 20 + spec.teapot);
      teapot_grade.student_png = images / (stem + "_teapot.png");
      teapot_grade.reference_png = images / "reference_teapot.png";
      TaskGrade program_grade;
      program_grade.task = "program";
      program_grade.points = spec.program;
      program_grade.max_points = 10;
      program_grade.visibility = Visibility::hidden;
      program_grade.reason = spec.program == 0 ? "the program ran past its 60 s limit" : "the program wrote its image";
      program_grade.program_output = spec.student == kScript ? kScriptOutput : std::string();
      program_grade.seconds = 1.5;
      s.tasks = {cow_grade, teapot_grade, program_grade};
      grades_.students.push_back(s);
    }
    std::sort(grades_.students.begin(), grades_.students.end(),
              [](const StudentGrade& a, const StudentGrade& b) { return a.student < b.student; });
    grades_.rubric = &rubric_;
    out_ = dir_ / "out";
  }

  // Runs the test venv's Python on a script of tests/python with `args`.
  static test::CommandResult python(const std::string& script, const std::vector<std::string>& args) {
    std::string command = fmt::format("{} {}", test::shell_quote(FARM_TEST_PYTHON),
                                      test::shell_quote(fmt::format("{}/tests/python/{}", FARM_SOURCE_DIR, script)));
    for (const std::string& a : args) command += fmt::format(" {}", test::shell_quote(a));
    return test::run_command(fmt::format("{} 2>&1", command));
  }

  // A CSV file as Python's csv module reads it: rows of fields.
  static std::vector<std::vector<std::string>> read_csv(const fs::path& file) {
    const test::CommandResult r = test::run_command(fmt::format(
        "{} -c {} {} 2>&1", test::shell_quote(FARM_TEST_PYTHON),
        test::shell_quote("import csv, json, sys\n"
                          "with open(sys.argv[1], newline='', encoding='utf-8') as f:\n"
                          "    print(json.dumps(list(csv.reader(f, strict=True))))\n"),
        test::shell_quote(file.string())));
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return nlohmann::json::parse(r.output).get<std::vector<std::vector<std::string>>>();
  }

  static std::string schema() { return std::string(FARM_TEST_DATA) + "/gradescope/results.schema.json"; }

  test::TempDir dir_;
  Rubric rubric_;
  ClassGrades grades_;
  fs::path out_;
};

// Every regular file under `root`, as paths relative to it.
std::set<std::string> files_under(const fs::path& root) {
  std::set<std::string> files;
  for (const auto& entry : fs::recursive_directory_iterator(root))
    if (entry.is_regular_file()) files.insert(fs::relative(entry.path(), root).string());
  return files;
}

TEST(GradePointsTest, PrintsUpToTwoDecimalsWithoutTrailingZeros) {
  EXPECT_EQ(format_points(60), "60");
  EXPECT_EQ(format_points(37.5), "37.5");
  EXPECT_EQ(format_points(12.25), "12.25");
  EXPECT_EQ(format_points(0), "0");
  EXPECT_EQ(format_points(-0.001), "0");
  EXPECT_EQ(format_points(33.333333), "33.33");
  EXPECT_EQ(format_points(19.999), "20");
  EXPECT_EQ(format_points(0.1 + 0.2), "0.3");
  EXPECT_DOUBLE_EQ(round_points(0.1 + 0.2), 0.3);
}

TEST(StudentFolderTest, KeepsOrdinaryIdsAndNeverClimbsOut) {
  EXPECT_EQ(student_folder_name("alice"), "alice");
  EXPECT_EQ(student_folder_name(kComma), kComma);
  EXPECT_EQ(student_folder_name(kScript), "<script>alert(1)<%2Fscript>");
  EXPECT_EQ(student_folder_name("."), "%2E");
  EXPECT_EQ(student_folder_name(".."), "%2E%2E");
  EXPECT_EQ(student_folder_name("../etc"), "..%2Fetc");
  EXPECT_EQ(student_folder_name("a\\b"), "a%5Cb");
  EXPECT_EQ(student_folder_name("50%"), "50%25");
  EXPECT_EQ(student_folder_name(std::string("a\nb\0c", 5)), "a%0Ab%00c");
  // Injective: the escape character is escaped too, so no two ids share a folder.
  EXPECT_NE(student_folder_name("%2E"), student_folder_name("."));
  EXPECT_NE(student_folder_name("a%2Fb"), student_folder_name("a/b"));
  EXPECT_THROW(student_folder_name(""), std::invalid_argument);
  EXPECT_EQ(url_path_segment("dave, \"x\" 50%"), "dave%2C%20%22x%22%2050%25");
}

TEST_F(GradeReportsTest, GradesCsvQuotesHostileIdsAndParsesBack) {
  const fs::path file = write_grades_csv(grades_, out_);
  EXPECT_EQ(file, out_ / "grades.csv");
  const std::string text = bytes_of(file);
  EXPECT_NE(text.find("\"dave, \"\"the\"\" hacker\",0,30,10,40,100\r\n"), std::string::npos) << text;
  const auto rows = read_csv(file);
  ASSERT_EQ(rows.size(), 6u);
  EXPECT_EQ(rows[0], (std::vector<std::string>{"student", "cow", "teapot", "program", "total", "maximum"}));
  // Sorted by id (bytes: '<' before letters).
  EXPECT_EQ(rows[1], (std::vector<std::string>{kScript, "20", "0", "0", "20", "100"}));
  EXPECT_EQ(rows[2], (std::vector<std::string>{"alice", "60", "30", "10", "100", "100"}));
  EXPECT_EQ(rows[3], (std::vector<std::string>{"bob", "37.5", "12.25", "0", "49.75", "100"}));
  EXPECT_EQ(rows[4], (std::vector<std::string>{"carol", "45", "30", "5", "80", "100"}));
  EXPECT_EQ(rows[5], (std::vector<std::string>{kComma, "0", "30", "10", "40", "100"}));
}

TEST_F(GradeReportsTest, GradesCsvSortsStudentsAndLeavesMissingTasksEmpty) {
  std::reverse(grades_.students.begin(), grades_.students.end());
  grades_.students.back().tasks.pop_back();  // the <script> student has no program grade
  const auto rows = read_csv(write_grades_csv(grades_, out_));
  ASSERT_EQ(rows.size(), 6u);
  EXPECT_EQ(rows[1], (std::vector<std::string>{kScript, "20", "0", "", "20", "100"}));
  EXPECT_EQ(rows[2][0], "alice");
  EXPECT_EQ(rows[5][0], kComma);
}

TEST_F(GradeReportsTest, FeedbackPagesAreSelfContainedAndEscaped) {
  const std::vector<fs::path> pages = write_feedback_pages(grades_, out_);
  ASSERT_EQ(pages.size(), 5u);
  const fs::path out = fs::weakly_canonical(out_);
  for (std::size_t i = 0; i < pages.size(); ++i) {
    const StudentGrade& s = grades_.students[i];
    const fs::path folder = out_ / "feedback" / student_folder_name(s.student);
    EXPECT_EQ(pages[i], folder / "index.html");
    ASSERT_TRUE(fs::is_regular_file(pages[i])) << pages[i];
    const std::string html = bytes_of(pages[i]);
    SCOPED_TRACE(s.student);
    EXPECT_NE(html.find("<h1>Feedback: " + markup_escape(s.student) + "</h1>"), std::string::npos);
    EXPECT_NE(html.find(fmt::format("<b>{} / 100</b>", format_points(points_total(s)))), std::string::npos);
    for (const TaskGrade& t : s.tasks) {
      EXPECT_NE(html.find(fmt::format("{} / {}", format_points(t.points), format_points(t.max_points))),
                std::string::npos);
      EXPECT_NE(html.find(markup_escape(t.reason)), std::string::npos) << t.reason;
    }
    EXPECT_NE(html.find(kHiddenTaskNote), std::string::npos);
    EXPECT_NE(html.find("flip_mean"), std::string::npos);
    // Nothing hostile comes through as markup; nothing is fetched from elsewhere.
    EXPECT_EQ(html.find("<script"), std::string::npos);
    EXPECT_EQ(html.find("<b>32x24"), std::string::npos);
    EXPECT_EQ(html.find("http"), std::string::npos);
    // Every picture the page shows is a file inside the student's folder.
    const std::regex src(R"re(<img src="([^"]*)")re");
    int images = 0;
    for (auto m = std::sregex_iterator(html.begin(), html.end(), src); m != std::sregex_iterator(); ++m, ++images) {
      const std::string name = (*m)[1];
      EXPECT_EQ(name.find('/'), std::string::npos) << name;
      EXPECT_TRUE(fs::is_regular_file(folder / name)) << name;
    }
    EXPECT_EQ(images, 5);  // cow: student, reference, difference; teapot: student, reference
    EXPECT_TRUE(fs::is_regular_file(folder / "cow.student.png"));
    EXPECT_TRUE(fs::is_regular_file(folder / "cow.reference.png"));
    EXPECT_TRUE(fs::is_regular_file(folder / "cow.difference.png"));
    EXPECT_TRUE(fs::is_regular_file(folder / "teapot.student.png"));
    EXPECT_EQ(bytes_of(folder / "cow.student.png"), bytes_of(s.tasks[0].student_png));
    // The folder lies inside the output folder, one level under feedback/.
    EXPECT_EQ(fs::weakly_canonical(folder).parent_path(), out / "feedback");
  }
  // The program output shows, escaped, in a <pre>.
  const std::string script_page = bytes_of(pages[0]);
  EXPECT_NE(script_page.find("<pre>" + markup_escape(kScriptOutput) + "</pre>"), std::string::npos) << script_page;
  EXPECT_NE(script_page.find("&lt;script&gt;alert(1)&lt;/script&gt;"), std::string::npos);
  // Nothing was written outside out/feedback: five folders of an index and five pictures.
  const std::set<std::string> files = files_under(out_);
  EXPECT_EQ(files.size(), 5u * 6u);
  for (const std::string& f : files) EXPECT_EQ(f.rfind("feedback/", 0), 0u) << f;
  EXPECT_EQ(files_under(dir_.path()).size(), files.size() + 13u);  // + the runner's images
}

TEST_F(GradeReportsTest, FeedbackPageSaysWhenAnImageIsMissing) {
  StudentGrade s = grades_.students[1];
  s.tasks[0].student_png = dir_ / "runner" / "gone.png";
  const fs::path page = write_feedback_page(s, nullptr, out_ / "one");
  const std::string html = bytes_of(page);
  EXPECT_NE(html.find("student image not available"), std::string::npos);
  EXPECT_FALSE(fs::exists(out_ / "one" / "cow.student.png"));
  EXPECT_TRUE(fs::exists(out_ / "one" / "cow.reference.png"));
}

TEST_F(GradeReportsTest, FeedbackPagesRefuseTwoStudentsWithOneId) {
  grades_.students.push_back(grades_.students.front());
  EXPECT_THROW(write_feedback_pages(grades_, out_), std::invalid_argument);
}

TEST_F(GradeReportsTest, GradescopeResultsFollowTheSpecification) {
  const std::vector<fs::path> files = write_gradescope_results(grades_, out_);
  ASSERT_EQ(files.size(), 5u);
  std::vector<std::string> args{schema()};
  for (std::size_t i = 0; i < files.size(); ++i) {
    const StudentGrade& s = grades_.students[i];
    EXPECT_EQ(files[i], out_ / "gradescope" / student_folder_name(s.student) / "results.json");
    args.push_back(files[i].string());
    const nlohmann::json j = nlohmann::json::parse(bytes_of(files[i]));
    SCOPED_TRACE(s.student);
    EXPECT_DOUBLE_EQ(j["score"].get<double>(), points_total(s));
    EXPECT_DOUBLE_EQ(j["execution_time"].get<double>(), 3.25);
    EXPECT_EQ(j["visibility"], "visible");
    EXPECT_EQ(j["stdout_visibility"], "hidden");
    EXPECT_EQ(j["output"], fmt::format("{} / 100 points over 3 tasks", format_points(points_total(s))));
    ASSERT_EQ(j["tests"].size(), 3u);
    for (std::size_t k = 0; k < 3; ++k) {
      const TaskGrade& t = s.tasks[k];
      const nlohmann::json& test = j["tests"][k];
      EXPECT_EQ(test["name"], t.task);
      EXPECT_DOUBLE_EQ(test["score"].get<double>(), t.points);
      EXPECT_DOUBLE_EQ(test["max_score"].get<double>(), t.max_points);
      EXPECT_EQ(test["status"], t.points == t.max_points ? "passed" : "failed");
      EXPECT_EQ(test["visibility"], gradescope_visibility(t.visibility));
      EXPECT_EQ(test["output"].get<std::string>().rfind(t.reason, 0), 0u);
      EXPECT_EQ(test["output_format"], "text");  // hostile text is never rendered as HTML
    }
    EXPECT_EQ(j["tests"][1]["visibility"], "after_published");
    EXPECT_EQ(j["tests"][2]["visibility"], "hidden");
  }
  const std::string script_output = nlohmann::json::parse(bytes_of(files[0]))["tests"][2]["output"];
  EXPECT_NE(script_output.find(kScriptOutput), std::string::npos);
  const test::CommandResult r = python("validate_json_schema.py", args);
  EXPECT_EQ(r.exit_code, 0) << r.output;
}

TEST_F(GradeReportsTest, GradescopeSingleResultsFileForTheContainer) {
  StudentGrade s = grades_.students[2];  // bob
  s.tasks[2].program_output = std::string("bad bytes \xff\xfe end");  // not UTF-8
  const fs::path file = out_ / "autograder" / "results" / "results.json";
  write_gradescope_results(s, file);
  const nlohmann::json j = nlohmann::json::parse(bytes_of(file));
  EXPECT_DOUBLE_EQ(j["score"].get<double>(), 49.75);
  EXPECT_NE(j["tests"][2]["output"].get<std::string>().find("bad bytes \xEF\xBF\xBD"), std::string::npos);
  const test::CommandResult r = python("validate_json_schema.py", {schema(), file.string()});
  EXPECT_EQ(r.exit_code, 0) << r.output;
}

TEST_F(GradeReportsTest, GradescopeSchemaRejectsBrokenResults) {
  const nlohmann::json good = gradescope_results_json(grades_.students[1]);
  const auto write = [&](const std::string& name, const nlohmann::json& j) {
    return dir_.write("broken/" + name + ".json", j.dump(2)).string();
  };
  nlohmann::json score_as_string = good;
  score_as_string["score"] = "37.5";
  nlohmann::json test_score_as_string = good;
  test_score_as_string["tests"][0]["score"] = "60";
  nlohmann::json unknown_status = good;
  unknown_status["tests"][0]["status"] = "partial";
  nlohmann::json unknown_visibility = good;
  unknown_visibility["tests"][1]["visibility"] = "after_publish";
  nlohmann::json no_score = good;  // neither a top-level score nor one on every test
  no_score.erase("score");
  no_score["tests"][1].erase("score");
  nlohmann::json misspelt = good;
  misspelt["tests"][0]["max_points"] = 60;
  nlohmann::json bad_format = good;
  bad_format["output_format"] = "markdown";
  const std::vector<std::string> broken = {write("score_as_string", score_as_string),
                                           write("test_score_as_string", test_score_as_string),
                                           write("unknown_status", unknown_status),
                                           write("unknown_visibility", unknown_visibility),
                                           write("no_score", no_score),
                                           write("misspelt", misspelt),
                                           write("bad_format", bad_format)};
  for (const std::string& file : broken) {
    const test::CommandResult r = python("validate_json_schema.py", {schema(), file});
    EXPECT_EQ(r.exit_code, 1) << file << "\n" << r.output;
  }
  // The same edits the specification allows pass: only the tests' scores, or only the top-level one.
  nlohmann::json tests_only = good;
  tests_only.erase("score");
  nlohmann::json score_only = good;
  score_only.erase("tests");
  const test::CommandResult r =
      python("validate_json_schema.py", {schema(), write("good", good), write("tests_only", tests_only),
                                         write("score_only", score_only)});
  EXPECT_EQ(r.exit_code, 0) << r.output;
}

TEST_F(GradeReportsTest, ClassSummaryHasTheFiguresAndTheHistogram) {
  const fs::path page = write_class_summary(grades_, out_);
  EXPECT_EQ(page, out_ / "summary.html");
  const std::string html = bytes_of(page);
  // totals 20, 100, 49.75, 80, 40: mean 57.95, median 49.75
  EXPECT_NE(html.find("<td class=\"n\"><b>57.95</b></td><td class=\"n\"><b>49.75</b></td>"), std::string::npos)
      << html;
  // cow 20 60 37.5 45 0: mean 32.5, median 37.5; teapot 0 30 12.25 30 30: 20.45, 30; program: 5, 5
  EXPECT_NE(html.find("<td>cow</td><td class=\"n\">60</td><td class=\"n\">32.5</td><td class=\"n\">37.5</td>"),
            std::string::npos);
  EXPECT_NE(html.find(">teapot <span class=\"hidden-note\">(hidden from students)</span></td><td class=\"n\">30</td>"
                      "<td class=\"n\">20.45</td><td class=\"n\">30</td>"),
            std::string::npos);
  EXPECT_NE(html.find("<td class=\"n\">10</td><td class=\"n\">5</td><td class=\"n\">5</td>"), std::string::npos);
  // Lost most: escaped ids linked to their feedback pages, and the reasons.
  EXPECT_NE(html.find("<a href=\"feedback/dave%2C%20%22the%22%20hacker/index.html\">dave, &quot;the&quot; hacker</a>"),
            std::string::npos);
  EXPECT_NE(html.find("&lt;script&gt;alert(1)&lt;/script&gt;</a></td><td class=\"n\">0 / 30</td>"
                      "<td class=\"reason\">teapot.png: expected &lt;b&gt;32x24&lt;/b&gt;, got 800x600</td>"),
            std::string::npos);
  EXPECT_EQ(html.find("<script"), std::string::npos);
  EXPECT_EQ(html.find("http"), std::string::npos);
  EXPECT_NE(html.find("<img src=\"summary-totals.png\""), std::string::npos);

  // The histogram: bars for 20 (bin 2), 40 and 49.75 (bin 4), 80 (bin 8), 100 (bin 9, inclusive).
  EXPECT_EQ(total_histogram(grades_), (std::vector<int>{0, 0, 1, 0, 2, 0, 0, 0, 1, 1}));
  const Image histogram = read_image(out_ / "summary-totals.png");
  ASSERT_EQ(histogram.width, kHistogramWidth);
  ASSERT_EQ(histogram.height, kHistogramHeight);
  const auto is_bar = [&](int x, int y) {
    for (int c = 0; c < 3; ++c)
      if (std::abs(histogram.at(x, y, c) - kHistogramBar[c]) > 0.5f / 255.0f) return false;
    return true;
  };
  // Each bar's height, along the column through its middle (bins are 44 pixels from x = 30).
  std::vector<int> heights;
  for (int bin = 0; bin < kHistogramBins; ++bin) {
    int height = 0;
    for (int y = 0; y < histogram.height; ++y) height += is_bar(30 + bin * 44 + 22, y) ? 1 : 0;
    heights.push_back(height);
  }
  EXPECT_GT(heights[4], 0);
  EXPECT_EQ(heights[4], 2 * heights[2]);
  EXPECT_EQ(heights[2], heights[8]);
  EXPECT_EQ(heights[8], heights[9]);
  EXPECT_EQ(heights[0] + heights[1] + heights[3] + heights[5] + heights[6] + heights[7], 0);
}

TEST(ClassSummaryTest, MedianOfOddAndEvenCounts) {
  EXPECT_DOUBLE_EQ(median_of({3, 1, 2}), 2);
  EXPECT_DOUBLE_EQ(median_of({4, 1, 3, 2}), 2.5);
  EXPECT_DOUBLE_EQ(median_of({}), 0);
}

TEST_F(GradeReportsTest, SimilarSubmissionsListsIdenticalAndNearlyIdenticalPairs) {
  const std::vector<SimilarPair> pairs = write_similar_submissions(grades_, out_);
  const auto rows = read_csv(out_ / "similar.csv");
  ASSERT_EQ(rows.size(), pairs.size() + 1);
  EXPECT_EQ(rows[0], (std::vector<std::string>{"task", "student_a", "student_b", "flip_mean", "identical"}));
  std::map<std::pair<std::string, std::string>, std::vector<std::string>> listed;
  for (std::size_t i = 1; i < rows.size(); ++i) {
    ASSERT_EQ(rows[i].size(), 5u);
    EXPECT_EQ(rows[i][0], "cow") << "teapot's alike images are the reference itself";
    listed[{rows[i][1], rows[i][2]}] = rows[i];
  }
  const std::pair<std::string, std::string> identical{"alice", "bob"}, near_pair{"alice", "carol"};
  ASSERT_TRUE(listed.count(identical));
  EXPECT_EQ(listed[identical][3], "0");
  EXPECT_EQ(listed[identical][4], "1");
  ASSERT_TRUE(listed.count(near_pair));
  EXPECT_EQ(listed[near_pair][4], "0");
  const double near = std::stod(listed[near_pair][3]);
  EXPECT_GT(near, 0.0);
  EXPECT_LT(near, 0.01);
  EXPECT_TRUE(listed.count(std::pair<std::string, std::string>{"bob", "carol"}));
  EXPECT_EQ(listed.size(), 3u);  // dave's and the <script> student's images are like nobody's
  EXPECT_EQ(rows[1][1], "alice");  // the identical pair first
  EXPECT_EQ(rows[1][2], "bob");
}

TEST_F(GradeReportsTest, SimilarSubmissionsCanListReferenceMatchesAndSkipsMissingImages) {
  grades_.students[1].tasks[0].student_png.clear();  // alice: no cow image
  SimilarityOptions options;
  options.skip_reference_matches = false;
  const std::vector<SimilarPair> pairs = find_similar_submissions(grades_, options);
  std::set<std::tuple<std::string, std::string, std::string>> listed;
  for (const SimilarPair& p : pairs) listed.insert({p.task, p.student_a, p.student_b});
  EXPECT_EQ(listed, (std::set<std::tuple<std::string, std::string, std::string>>{
                        {"cow", "bob", "carol"}, {"teapot", "alice", kComma}}));
}

}  // namespace
}  // namespace farm

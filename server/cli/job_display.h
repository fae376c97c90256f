#pragma once
// How the client commands (`farm submit --wait`, `status`, `watch`, `cancel`) show a job on the
// scheduler: its summary, a progress line, and following it to its end.
#include <fmt/format.h>

#include <functional>
#include <string>
#include <vector>

#include "proto/farm.pb.h"
#include "server/client/scheduler_client.h"
#include "server/common/proto_json.h"

namespace farm {

// "3/12 tiles"; for a job with frames "2/48 frames, 610/14400 tiles".
std::string progress_of(const v1::Job& job);
// "2/48 frames"; empty for a still.
std::string frames_of(const v1::Job& job);

// A Timestamp in local time, "2024-05-01 12:00:00"; "-" when unset.
std::string local_time(const google::protobuf::Timestamp& t);

// Its state in a word, "paused" for a paused job that is not final.
std::string state_label(const v1::Job& job);

// The messages as one JSON array on stdout, an element a line.
template <typename Message>
void print_json_array(const std::vector<Message>& items) {
  std::string out = "[";
  for (std::size_t i = 0; i < items.size(); ++i) out += (i == 0 ? "" : ",\n ") + json_of(items[i]);
  fmt::print("{}]\n", out);
}

// What an event says, in one line: "running -> failed: tile 3 failed 3 times ...",
// "tiles 4-7 failed on 10.0.0.2:50061: deadline exceeded (will retry)", "frame 3 merged", ...
std::string describe_event(const v1::JobEvent& event);
// A log entry as `farm log` prints it: its local time (to the millisecond) and describe_event.
void print_log_entry(const v1::JobLogEntry& entry);

// The job's state, settings, times and render statistics, one item a line.
void print_job(const v1::Job& job);

// Follows a job to its end with a progress bar (on a terminal) or a line per state change, and
// reports failed tiles on stderr. Returns the job as it ended.
// `also` (when given) sees every event too, after the progress bar.
v1::Job follow(SchedulerClient& client, const std::string& job_id,
               const std::function<void(const v1::JobEvent&)>& also = {});

// 0 when the job succeeded; else says how it ended on stderr and returns 1.
int exit_code_of(const v1::Job& job);

}  // namespace farm

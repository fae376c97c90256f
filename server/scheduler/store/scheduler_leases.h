#pragma once
// The job store's leases and claims (job_store.h), for several schedulers on one PostgreSQL store:
// the id this scheduler marks the units it hands out with, its lease, the reaping of schedulers
// whose lease ran out, and the claims on the merges and ends that one scheduler must do alone.
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "proto/farm.pb.h"
#include "server/scheduler/store/store_part.h"

namespace farm {

class SchedulerLeases : public StorePart {
 public:
  explicit SchedulerLeases(StoreSession& session) : StorePart(session) {}

  // Several schedulers on one store (PostgreSQL). Each marks the tiles it hands out with its id
  // (set_scheduler, once, before any claim; "" until then) and the batch operations below act only
  // on tiles this store's scheduler handed out. A scheduler holds a lease in the store, renewed
  // (hold_lease) well before it runs out; when one runs out (the scheduler was killed, or lost the
  // store or its machine), any other's reap_expired queues its running tiles again with no
  // attempt counted, and a late answer to the dead one finds them running no more.
  void set_scheduler(const std::string& id);
  const std::string& scheduler() const { return scheduler_; }  // set once, before any thread asks
  void hold_lease(std::int64_t until_ms);
  // The lease given up (a scheduler that stops): its running tiles are queued again by itself.
  void drop_lease();
  // Every other scheduler whose lease ran out before `now_ms`: its running tiles queued again, its
  // claims (below) and its lease gone. One transaction.
  std::vector<ReapedScheduler> reap_expired(std::int64_t now_ms);
  // Work on a job that one scheduler must do alone, though several may find it to do: merging a
  // frame whose units are all done, ending a job whose frames are all merged. True when it is this
  // store's scheduler's (claimed now, or before); false when another holds it. A claim lasts
  // while its scheduler's lease does; a frame's, until a part of it is taken back.
  bool claim_frame_merge(const std::string& job_id, int frame);
  bool claim_job_end(const std::string& job_id);

 private:
  bool claim_locked(const std::string& job_id, const std::string& what);
};

}  // namespace farm

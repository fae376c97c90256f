#include "server/scheduler/jobs/setbacks.h"

#include "server/common/disk_full.h"

namespace farm {

void rethrow_if_setback() {
  try {
    throw;
  } catch (const DiskFull&) {
    throw;
  } catch (const StoreUnavailable&) {
    throw;
  } catch (...) {
  }
}

Setback Setbacks::report_current() {
  try {
    throw;
  } catch (const DiskFull& e) {
    pause_.report(e);
    return Setback::disk_full;
  } catch (const StoreUnavailable& e) {
    outage_.report(e);
    return Setback::store_away;
  } catch (...) {
    return Setback::none;
  }
}

}  // namespace farm

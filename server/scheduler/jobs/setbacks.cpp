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

bool Setbacks::report_current() {
  try {
    throw;
  } catch (const DiskFull& e) {
    pause_.report(e);
    return true;
  } catch (const StoreUnavailable& e) {
    outage_.report(e);
    return true;
  } catch (...) {
    return false;
  }
}

}  // namespace farm

#include "server/common/service_error.h"

#include <new>

#include "renderer/scene/input_error.h"
#include "server/common/scene_materializer.h"

namespace farm {

grpc::Status status_of_current_exception() {
  try {
    throw;
  } catch (const ServiceError& e) {
    return e.status();
  } catch (const MissingAssetsError& e) {
    return {grpc::StatusCode::FAILED_PRECONDITION, e.what()};
  } catch (const InputError& e) {
    return {grpc::StatusCode::INVALID_ARGUMENT, e.what()};
  } catch (const std::bad_alloc&) {
    return {grpc::StatusCode::RESOURCE_EXHAUSTED, "out of memory"};
  } catch (const std::exception& e) {
    return {grpc::StatusCode::INTERNAL, e.what()};
  }
}

}  // namespace farm

#pragma once
// The capture requests a service has heard the coordinator send (CAPTURE_REQUEST): the registration
// and mapping services take a CLOUD or a REGISTERED_CLOUD only when it answers one of them. Request
// ids are drawn at random per scan (first_request_id, [2^32, 2^62)), so a sender that has not seen
// the scan's requests cannot forge a view the pipeline takes; a real answer that comes before its
// request was heard (a service restarted in between) is refused once and taken when the
// coordinator asks again (it re-sends the capture request while the view's answers are late).
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>

#include "bus/reply_cache.hpp"

namespace pbnbv::bus {

class AskedCaptures {
 public:
  // Remembers the `kept` requests heard last (a flood of forged requests pushes real ones out:
  // their answers are refused until the coordinator asks again).
  explicit AskedCaptures(std::size_t kept = 64) : asked_(kept) {}

  void heard(const std::string& scan_id, int64_t request_id) { asked_.put({scan_id, request_id}, true); }
  bool asked(const std::string& scan_id, int64_t request_id) const {
    return asked_.find({scan_id, request_id}) != nullptr;
  }
  // Throws std::invalid_argument naming the message when it answers no request heard: the bus
  // counts and logs it as rejected.
  void require(const std::string& what, const std::string& scan_id, int64_t request_id) const {
    if (!asked(scan_id, request_id)) {
      throw std::invalid_argument(what + " of scan '" + scan_id + "' answers request " + std::to_string(request_id) +
                                  ", which no CAPTURE_REQUEST heard here asked for");
    }
  }

 private:
  ReplyCache<std::pair<std::string, int64_t>, bool> asked_;
};

}  // namespace pbnbv::bus

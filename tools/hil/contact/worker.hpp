#pragma once
/// \file `hil contact worker`: subscribes to PoseWrenchSample, publishes ContactEstimate.
#include <CLI/CLI.hpp>

#include "hil/contact_id/online.hpp"
#include "hil_msgsPubSubTypes.h"

namespace hil::cli {

/// The ContactEstimate message for one online estimate.
hil_msgs::msg::ContactEstimate to_message(const contact_id::OnlineEstimate& e);

void add_contact_worker(CLI::App& contact);

}  // namespace hil::cli

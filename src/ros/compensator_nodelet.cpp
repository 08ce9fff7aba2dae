// Nodelet: creates the CompensatorRos wrapper on the nodelet's node handles.
#include <exception>
#include <memory>

#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>

#include "periodic_bias_compensation/ros/compensator_ros.h"

namespace periodic_bias_compensation
{
class CompensatorNodelet : public nodelet::Nodelet
{
private:
  void onInit() override
  {
    try
    {
      compensator_ = std::make_unique<CompensatorRos>(getNodeHandle(), getPrivateNodeHandle());
    }
    catch (const std::exception& e)
    {
      NODELET_FATAL("bias compensation not started: %s", e.what());
      throw;
    }
  }

  std::unique_ptr<CompensatorRos> compensator_;
};
}  // namespace periodic_bias_compensation

PLUGINLIB_EXPORT_CLASS(periodic_bias_compensation::CompensatorNodelet, nodelet::Nodelet)

# ROS wrapper, nodelet, node, offline bag tools and rostests.

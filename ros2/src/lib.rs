//! ldcbf-nav ROS 2 node.

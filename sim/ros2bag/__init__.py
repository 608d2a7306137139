"""ROS 2 bag export of a mission (rosbag2 folder, MCAP storage) through the rosbags library."""

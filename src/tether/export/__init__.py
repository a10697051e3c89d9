"""Run folders in other tools' formats (ROS 2: MCAP and rosbag2)."""

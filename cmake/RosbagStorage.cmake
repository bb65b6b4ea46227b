# vio::rosbag: ROS 1 bag reading and writing without ROS, from Debian's
# librosbag-storage-dev and libsensor-msgs-dev (tools/install_deps.sh).
#
# Their pkg-config files require packages Debian does not ship (pluginlib's
# ROS 1 .pc), and rosbag/bag.h includes pluginlib, whose Debian build is the
# ROS 2 one with its headers one folder deeper; so the headers and libraries
# are found here directly.
find_path(ROSBAG_INCLUDE_DIR rosbag/bag.h REQUIRED)
find_path(SENSOR_MSGS_INCLUDE_DIR sensor_msgs/Image.h REQUIRED)
set(rosbag_libraries)
foreach(lib rosbag_storage roscpp_serialization rostime cpp_common console_bridge boost_filesystem)
  find_library(ROSBAG_LIB_${lib} ${lib} REQUIRED)
  list(APPEND rosbag_libraries ${ROSBAG_LIB_${lib}})
endforeach()
set(rosbag_includes ${ROSBAG_INCLUDE_DIR} ${SENSOR_MSGS_INCLUDE_DIR})
foreach(dir pluginlib class_loader rcpputils rcutils ament_index_cpp)
  find_path(ROSBAG_DEP_${dir} NAMES ${dir} PATHS /usr/include/${dir} NO_DEFAULT_PATH REQUIRED)
  list(APPEND rosbag_includes ${ROSBAG_DEP_${dir}})
endforeach()
add_library(vio_rosbag INTERFACE)
target_include_directories(vio_rosbag SYSTEM INTERFACE ${rosbag_includes})
target_link_libraries(vio_rosbag INTERFACE ${rosbag_libraries})
add_library(vio::rosbag ALIAS vio_rosbag)

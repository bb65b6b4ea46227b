# vio::ros2_storage: what the ROS 2 recording readers and writers
# (tools/dataset: MCAP, rosbag2 sqlite3, CDR) link, from Debian's libzstd-dev,
# liblz4-dev and libsqlite3-dev (tools/install_deps.sh; the MCAP chunk CRC is
# libdeflate's).
find_package(PkgConfig REQUIRED)
pkg_check_modules(VIO_ZSTD REQUIRED IMPORTED_TARGET libzstd)
pkg_check_modules(VIO_LZ4 REQUIRED IMPORTED_TARGET liblz4)
pkg_check_modules(VIO_SQLITE3 REQUIRED IMPORTED_TARGET sqlite3)
add_library(vio_ros2_storage INTERFACE)
target_link_libraries(vio_ros2_storage INTERFACE PkgConfig::VIO_ZSTD PkgConfig::VIO_LZ4 PkgConfig::VIO_SQLITE3)
add_library(vio::ros2_storage ALIAS vio_ros2_storage)

# Every dependency lookup in one file. All come from Debian packages (apt-get) or PyPI; nothing
# is downloaded at configure time (no FetchContent). `make deps` installs them.
#   Eigen3   libeigen3-dev      public: the only type library in public headers
#   CGAL     libcgal-dev        private: 2-D Delaunay triangulation (wifi)
#   Ceres    libceres-dev       private: sparse least squares (network, wifi refinement);
#                               SuiteSparse (CHOLMOD, SPQR) comes through Ceres' link interface
#   nanoflann libnanoflann-dev  private, header-only: exact kNN on kd-trees (analog)
#   SQLite3  libsqlite3-dev     private: the site file reader (fusion/site_file.cc)
#   GTest    libgtest-dev       tests only
#   pybind11 PyPI (>= 2.10)     bindings only
find_package(Eigen3 3.3 REQUIRED NO_MODULE)
find_package(Threads REQUIRED)

# CGAL and Ceres are needed by subsystems, not by core; they are still required here so that a
# machine missing them fails at configure time with a clear message, not halfway through a build.
set(CGAL_DO_NOT_WARN_ABOUT_CMAKE_BUILD_TYPE TRUE)
# CGAL 5.5's config calls the removed FindBoost module; Boost 1.74 ships BoostConfig.cmake.
set(CMAKE_POLICY_DEFAULT_CMP0167 NEW)
find_package(CGAL 5.0 REQUIRED)
find_package(Ceres 2.0 REQUIRED)
find_package(nanoflann REQUIRED)
find_package(SQLite3 REQUIRED)  # CMake's FindSQLite3 (>= 3.14): target SQLite::SQLite3

if(INDOORLOC_BUILD_TESTS)
  find_package(GTest REQUIRED)
endif()

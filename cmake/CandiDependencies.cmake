# Every third-party package candi uses, found once here so a missing one fails at configure time
# with its name (scripts/deps.sh installs them all). Names verified in BUILD_NOTES.md.
find_package(PkgConfig REQUIRED)
find_package(Threads REQUIRED)
find_package(Eigen3 3.3 REQUIRED NO_MODULE)
find_package(PNG REQUIRED)
find_package(TBB REQUIRED)
find_package(OpenMP REQUIRED COMPONENTS CXX)
find_package(fmt REQUIRED)
find_package(spdlog REQUIRED)
find_package(CLI11 REQUIRED)
find_package(nlohmann_json 3 REQUIRED)
# mesh
find_package(CGAL REQUIRED)
find_package(OpenMesh CONFIG REQUIRED)   # CONFIG: CGAL ships a FindOpenMesh that fails (trap 1)
pkg_check_modules(DXFLIB REQUIRED IMPORTED_TARGET dxflib)
# sampling
find_package(nanoflann REQUIRED)
# reconstruction
find_package(Ceres REQUIRED)
find_package(OpenCV REQUIRED COMPONENTS core imgproc imgcodecs)
find_package(Torch REQUIRED)
find_package(PCL REQUIRED COMPONENTS common io kdtree search registration filters)
find_program(COLMAP_EXECUTABLE colmap)
if(NOT COLMAP_EXECUTABLE)
  message(WARNING "colmap not found: `candi sfm` will report it at run time")
endif()
# render scale-out; C as well as CXX or VTK::mpi fails (trap 2)
find_package(MPI REQUIRED COMPONENTS C CXX)
find_program(MPIEXEC_EXECUTABLE NAMES mpirun mpiexec)
# tests and benchmarks
find_package(GTest REQUIRED)
find_package(benchmark REQUIRED)

# find_package(PCL) on Debian 12 with the two fixes its PCL 1.13 needs (pcl-spec.md sections 9, 10).
# Used by the programs that compare against PCL (tools/pcl_reference, bench/pcl); viewpose itself
# never needs PCL. Usage: viewpose_find_pcl(<component>...), then PCL_INCLUDE_DIRS, PCL_DEFINITIONS
# and PCL_LIBRARIES as find_package(PCL) sets them.
macro(viewpose_find_pcl)
  # PCL's config finds VTK 9.1, whose VTK::mpi wants an MPI::MPI_C target Debian 12 does not
  # provide, and configuration fails. Nothing here uses MPI: an empty target satisfies it.
  if(NOT TARGET MPI::MPI_C)
    add_library(MPI::MPI_C INTERFACE IMPORTED)
  endif()
  find_package(PCL 1.13 REQUIRED COMPONENTS ${ARGN})
  # VTK's kissfft target leaks kiss_fft_scalar=double into anything linking PCL, and header-only
  # PCL code (CRHAlignment's roll FFT) then disagrees with libpcl_common's float build.
  list(FILTER PCL_DEFINITIONS EXCLUDE REGEX "kiss_fft_scalar")
  if(TARGET VTK::kissfft)
    set_target_properties(VTK::kissfft PROPERTIES INTERFACE_COMPILE_DEFINITIONS "")
  endif()
endmacro()

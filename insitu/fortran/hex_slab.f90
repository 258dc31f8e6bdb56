! SPDX-License-Identifier: BSD-3-Clause
! insitu/fortran/hex_slab.f90 -- the Fortran examples' mesh: the z layers k0 .. k1 - 1 of an n^3
! grid of hexahedra over the unit cube, with the points of layers k0 .. k1, as the C API takes them
module hex_slab
  use, intrinsic :: iso_c_binding
  implicit none
  private
  public :: hex_slab_points, hex_slab_cells

contains

  !> The points of layers k0 .. k1, x fastest, then y, then z: (n + 1)^2 (k1 - k0 + 1) of them.
  subroutine hex_slab_points(n, k0, k1, xyz)
    integer, intent(in) :: n, k0, k1
    real(c_double), intent(out) :: xyz(:, :)
    integer :: i, j, k
    do k = k0, k1
      do j = 0, n
        do i = 0, n
          xyz(:, 1 + point_id(n, k0, i, j, k)) = [real(i, c_double), real(j, c_double), real(k, c_double)] / n
        end do
      end do
    end do
  end subroutine

  !> The cells of layers k0 .. k1 - 1 in VTK's hexahedron order: n^2 (k1 - k0) of them, each naming
  !> its points zero-based, as the C API expects.
  subroutine hex_slab_cells(n, k0, k1, conn)
    integer, intent(in) :: n, k0, k1
    integer(c_int32_t), intent(out) :: conn(:, :)
    integer :: i, j, k, c
    c = 0
    do k = k0, k1 - 1
      do j = 0, n - 1
        do i = 0, n - 1
          c = c + 1
          conn(:, c) = [point_id(n, k0, i, j, k), point_id(n, k0, i + 1, j, k), point_id(n, k0, i + 1, j + 1, k), &
                        point_id(n, k0, i, j + 1, k), point_id(n, k0, i, j, k + 1), point_id(n, k0, i + 1, j, k + 1), &
                        point_id(n, k0, i + 1, j + 1, k + 1), point_id(n, k0, i, j + 1, k + 1)]
        end do
      end do
    end do
  end subroutine

  integer(c_int32_t) function point_id(n, k0, i, j, k)
    integer, intent(in) :: n, k0, i, j, k
    point_id = int(i + (n + 1) * (j + (n + 1) * (k - k0)), c_int32_t)
  end function

end module hex_slab

! SPDX-License-Identifier: BSD-3-Clause
! insitu/fortran/penumbra.f90 -- Fortran 2003 bindings to Penumbra's C API (penumbra.h).
! The same symbols as the C API, bound with bind(C); there is no second implementation.
module penumbra
  use, intrinsic :: iso_c_binding
  implicit none
  private

  integer(c_int), parameter, public :: PNB_OK = 0, PNB_INVALID_ARGUMENT = 1, PNB_INVALID_OPERATION = 2, &
       PNB_OUT_OF_MEMORY = 3, PNB_BACKEND_UNAVAILABLE = 4, PNB_INTERNAL_ERROR = 5, PNB_IO_ERROR = 6
  integer(c_int), parameter, public :: PNB_BORROW = 0, PNB_COPY = 1
  integer(c_int), parameter, public :: PNB_FLOAT32 = 0, PNB_FLOAT64 = 1, PNB_INT32 = 2, PNB_INT64 = 3
  integer(c_int), parameter, public :: PNB_POINT_FIELD = 0, PNB_CELL_FIELD = 1
  integer(c_int8_t), parameter, public :: PNB_TETRA = 10, PNB_HEXAHEDRON = 12, PNB_WEDGE = 13, PNB_PYRAMID = 14

  !> Mirror of pnb_mesh_desc (same member order, so the same layout).
  type, bind(C), public :: pnb_mesh_desc
    type(c_ptr) :: points = c_null_ptr
    integer(c_int64_t) :: point_count = 0
    integer(c_int64_t) :: point_stride_bytes = 0
    integer(c_int) :: point_type = PNB_FLOAT64
    type(c_ptr) :: connectivity = c_null_ptr
    integer(c_int64_t) :: connectivity_count = 0
    type(c_ptr) :: offsets = c_null_ptr
    integer(c_int) :: index_type = PNB_INT64
    type(c_ptr) :: cell_types = c_null_ptr
    integer(c_int64_t) :: cell_types_count = 0
    integer(c_int64_t) :: topology_version = 0
  end type

  !> Mirror of pnb_field_desc. `name` must point at a NUL-terminated character array.
  type, bind(C), public :: pnb_field_desc
    type(c_ptr) :: name = c_null_ptr
    integer(c_int) :: association = PNB_POINT_FIELD
    type(c_ptr) :: values = c_null_ptr
    integer(c_int64_t) :: count = 0
    integer(c_int) :: components = 1
    integer(c_int64_t) :: stride_bytes = 0
    integer(c_int) :: type = PNB_FLOAT64
  end type

  !> Mirror of pnb_step_stats (pnb_last_step).
  type, bind(C), public :: pnb_step_stats
    integer(c_int64_t) :: cycle = 0
    integer(c_int) :: images = 0
    real(c_double) :: render_ms = 0, total_ms = 0, light_ms = 0, light_residual = 0
    integer(c_int) :: light_converged = 0
  end type

  public :: pnb_create, pnb_check_config, pnb_publish_mesh, pnb_publish_field, pnb_execute, pnb_finalize, pnb_destroy
  public :: pnb_last_step
  public :: pnb_last_error_message

  interface
    integer(c_int) function pnb_create(config, ctx) bind(C, name="pnb_create")
      import :: c_int, c_char, c_ptr
      character(kind=c_char), dimension(*), intent(in) :: config
      type(c_ptr), intent(out) :: ctx
    end function
    integer(c_int) function pnb_check_config(config) bind(C, name="pnb_check_config")
      import :: c_int, c_char
      character(kind=c_char), dimension(*), intent(in) :: config
    end function
    integer(c_int) function pnb_publish_mesh(ctx, mesh, own) bind(C, name="pnb_publish_mesh")
      import :: c_int, c_ptr, pnb_mesh_desc
      type(c_ptr), value :: ctx
      type(pnb_mesh_desc), intent(in) :: mesh
      integer(c_int), value :: own
    end function
    integer(c_int) function pnb_publish_field(ctx, field, own) bind(C, name="pnb_publish_field")
      import :: c_int, c_ptr, pnb_field_desc
      type(c_ptr), value :: ctx
      type(pnb_field_desc), intent(in) :: field
      integer(c_int), value :: own
    end function
    integer(c_int) function pnb_execute(ctx, time, cycle) bind(C, name="pnb_execute")
      import :: c_int, c_ptr, c_double, c_int64_t
      type(c_ptr), value :: ctx
      real(c_double), value :: time
      integer(c_int64_t), value :: cycle
    end function
    integer(c_int) function pnb_last_step(ctx, stats) bind(C, name="pnb_last_step")
      import :: c_int, c_ptr, pnb_step_stats
      type(c_ptr), value :: ctx
      type(pnb_step_stats), intent(out) :: stats
    end function
    integer(c_int) function pnb_finalize(ctx) bind(C, name="pnb_finalize")
      import :: c_int, c_ptr
      type(c_ptr), value :: ctx
    end function
    subroutine pnb_destroy(ctx) bind(C, name="pnb_destroy")
      import :: c_ptr
      type(c_ptr), value :: ctx
    end subroutine
    type(c_ptr) function pnb_last_error_c(ctx) bind(C, name="pnb_last_error")
      import :: c_ptr
      type(c_ptr), value :: ctx
    end function
    integer(c_size_t) function c_strlen(s) bind(C, name="strlen")
      import :: c_ptr, c_size_t
      type(c_ptr), value :: s
    end function
  end interface

contains

  !> The last error on ctx (or of the last failed pnb_create when ctx is c_null_ptr), as a
  !> Fortran string.
  function pnb_last_error_message(ctx) result(message)
    type(c_ptr), intent(in) :: ctx
    character(len=:), allocatable :: message
    type(c_ptr) :: p
    character(kind=c_char), pointer :: chars(:)
    integer :: i, n
    p = pnb_last_error_c(ctx)
    n = int(c_strlen(p))
    call c_f_pointer(p, chars, [n])
    allocate(character(len=n) :: message)
    do i = 1, n
      message(i:i) = chars(i)
    end do
  end function

end module penumbra

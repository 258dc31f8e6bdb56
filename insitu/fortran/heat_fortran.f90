! SPDX-License-Identifier: BSD-3-Clause
! insitu/fortran/heat_fortran.f90 -- a Fortran caller: explicit heat diffusion on a hex grid,
! rendered through the C API. Usage: penumbra-example-fortran [OUTPUT_DIR]
program heat_fortran
  use, intrinsic :: iso_c_binding
  use penumbra
  use hex_slab
  implicit none
  integer, parameter :: n = 12, np = (n + 1)**3, nc = n**3, steps = 20
  real(c_double), target :: xyz(3, np), temp(np), next(np)
  integer(c_int32_t), target :: conn(8, nc)
  integer(c_int8_t), target :: types(1)
  character(kind=c_char, len=32), target :: field_name
  character(len=256) :: outdir
  character(len=:), allocatable :: config
  type(c_ptr) :: ctx
  type(pnb_mesh_desc) :: mesh
  type(pnb_field_desc) :: field
  type(pnb_step_stats) :: stats
  type(pnb_needs) :: needs
  integer :: asked_to_render = 0
  integer :: s, status

  ! The types' struct_size defaults must be their C sizes (insitu/fortran/CMakeLists.txt).
  if (mesh%struct_size /= c_sizeof(mesh) .or. field%struct_size /= c_sizeof(field) .or. &
      stats%struct_size /= c_sizeof(stats)) error stop 'penumbra module: struct sizes differ from the C ones'
  outdir = 'penumbra-fortran-db'
  if (command_argument_count() >= 1) call get_command_argument(1, outdir)

  call hex_slab_points(n, 0, n, xyz)
  call hex_slab_cells(n, 0, n, conn)
  temp = exp(-40.0d0 * sum((xyz - 0.5d0)**2, dim=1))
  types(1) = PNB_HEXAHEDRON

  config = '{"output":{"directory":"' // trim(outdir) // '","if_exists":"resume"},' // &
           '"image":{"width":96,"height":96},"cameras":{"phi":[30],"theta":[20]},' // &
           '"fields":[{"name":"temperature","range":[0,1],"transfer_function":{' // &
           '"colors":[[0,0.2,0.3,0.9],[1,1,0.4,0.1]],"opacities":[[0,0],[1,8]]}}],' // &
           '"trigger":{"every_cycles":5}}'
  status = pnb_create(config // c_null_char, ctx)
  deallocate(config)  ! the main program's allocatables are never freed by themselves
  if (status /= PNB_OK) then
    print *, 'pnb_create failed: ', pnb_last_error_message(c_null_ptr)
    stop 1
  end if

  mesh%points = c_loc(xyz)
  mesh%point_count = np
  mesh%point_type = PNB_FLOAT64
  mesh%connectivity = c_loc(conn)
  mesh%connectivity_count = 8 * nc
  mesh%index_type = PNB_INT32
  mesh%cell_types = c_loc(types)
  mesh%cell_types_count = 1
  mesh%topology_version = 1
  call check(pnb_publish_mesh(ctx, mesh, PNB_BORROW))

  field_name = 'temperature' // c_null_char
  field%name = c_loc(field_name)
  field%association = PNB_POINT_FIELD
  field%values = c_loc(temp)
  field%count = np
  field%type = PNB_FLOAT64
  do s = 0, steps
    ! Asked first: only a step that renders or stores reads the field.
    call check(pnb_step_needs(ctx, 0.01d0 * s, int(s, c_int64_t), needs))
    if (needs%renders /= 0 .or. needs%stores /= 0) then
      if (pnb_needed_field_name(ctx, 0) /= 'temperature') stop 'pnb_needed_field: not temperature'
      call check(pnb_publish_field(ctx, field, PNB_BORROW))
    end if
    asked_to_render = asked_to_render + needs%renders
    call check(pnb_execute(ctx, 0.01d0 * s, int(s, c_int64_t)))
    call diffuse()
  end do
  call check(pnb_last_step(ctx, stats))
  print '(a,i0,a,i0,a)', 'last rendered step: cycle ', stats%cycle, ', ', stats%images, ' image(s)'
  print '(a,i0,a,f0.3,a,f0.3,a)', 'steps that rendered, as pnb_step_needs said: ', asked_to_render, &
    '; last step ', stats%total_ms, ' ms, of which writing ', stats%write_ms, ' ms'
  call check(pnb_finalize(ctx))
  call pnb_destroy(ctx)
  print '(a)', 'wrote ' // trim(outdir)

contains

  subroutine diffuse()
    integer :: a, b, q, r
    next = temp
    do r = 1, n - 1
      do b = 1, n - 1
        do a = 1, n - 1
          q = 1 + a + (n + 1) * (b + (n + 1) * r)
          next(q) = temp(q) + 0.1d0 * (temp(q - 1) + temp(q + 1) + temp(q - (n + 1)) + temp(q + (n + 1)) + &
                    temp(q - (n + 1)**2) + temp(q + (n + 1)**2) - 6 * temp(q))
        end do
      end do
    end do
    temp = next
  end subroutine

  subroutine check(st)
    integer(c_int), intent(in) :: st
    if (st /= PNB_OK) then
      print *, 'penumbra error: ', pnb_last_error_message(ctx)
      stop 2
    end if
  end subroutine

end program heat_fortran

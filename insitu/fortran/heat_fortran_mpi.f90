! SPDX-License-Identifier: BSD-3-Clause
! insitu/fortran/heat_fortran_mpi.f90 -- a Fortran caller over MPI ranks: each rank owns a slab of
! z layers of a hex grid (the points of the layers between slabs on both ranks) and publishes a
! warm spot drifting through it; one image database, whatever the rank count (past 12 ranks some
! own no layer and publish an empty part). Usage: mpirun -np N penumbra-example-fortran-mpi [OUTPUT_DIR]
program heat_fortran_mpi
  use, intrinsic :: iso_c_binding
  use mpi
  use penumbra
  use hex_slab
  implicit none
  integer, parameter :: n = 12, steps = 10
  real(c_double), allocatable, target :: xyz(:, :), temp(:)
  integer(c_int32_t), allocatable, target :: conn(:, :)
  integer(c_int8_t), target :: types(1)
  character(kind=c_char, len=32), target :: field_name
  character(len=256) :: outdir
  type(c_ptr) :: ctx
  type(pnb_mesh_desc) :: mesh
  type(pnb_field_desc) :: field
  type(pnb_step_stats) :: stats
  integer :: rank, ranks, ierr, k0, k1, np, nc, s
  integer(c_int) :: status

  call MPI_Init(ierr)
  call MPI_Comm_rank(MPI_COMM_WORLD, rank, ierr)
  call MPI_Comm_size(MPI_COMM_WORLD, ranks, ierr)
  outdir = 'penumbra-fortran-mpi-db'
  if (command_argument_count() >= 1) call get_command_argument(1, outdir)

  ! This rank's cells: z layers k0 .. k1 - 1; its points: layers k0 .. k1 (none when it owns no layer).
  k0 = rank * n / ranks
  k1 = (rank + 1) * n / ranks
  np = merge((n + 1)**2 * (k1 - k0 + 1), 0, k1 > k0)
  nc = n**2 * (k1 - k0)
  allocate(xyz(3, np), temp(np), conn(8, nc))
  if (np > 0) then
    call hex_slab_points(n, k0, k1, xyz)
    call hex_slab_cells(n, k0, k1, conn)
  end if
  types(1) = PNB_HEXAHEDRON

  ctx = c_null_ptr
  call check(pnb_create_mpi('{"output":{"directory":"' // trim(outdir) // '"},' // &
                            '"image":{"width":96,"height":96},"cameras":{"phi":[30,120],"theta":[20]},' // &
                            '"fields":[{"name":"temperature","range":[0,1],"transfer_function":{' // &
                            '"colors":[[0,0.2,0.3,0.9],[1,1,0.4,0.1]],"opacities":[[0,0],[1,8]]}}],' // &
                            '"trigger":{"every_cycles":5}}' // c_null_char, MPI_COMM_WORLD, ctx))

  mesh%point_count = np
  mesh%point_type = PNB_FLOAT64
  mesh%connectivity_count = 8 * nc
  mesh%index_type = PNB_INT32
  mesh%topology_version = 1
  if (nc > 0) then
    mesh%points = c_loc(xyz)
    mesh%connectivity = c_loc(conn)
    mesh%cell_types = c_loc(types)
    mesh%cell_types_count = 1
  else  ! an empty part: every count 0
    mesh%cell_types_count = 0
  end if
  call check(pnb_publish_mesh(ctx, mesh, PNB_BORROW))

  field_name = 'temperature' // c_null_char
  field%name = c_loc(field_name)
  field%association = PNB_POINT_FIELD
  if (np > 0) field%values = c_loc(temp)
  field%count = np
  field%type = PNB_FLOAT64
  do s = 0, steps
    temp = exp(-40.0d0 * ((xyz(1, :) - 0.3d0 - 0.04d0 * s)**2 + (xyz(2, :) - 0.5d0)**2 + (xyz(3, :) - 0.5d0)**2))
    ! Local: a field refused here fails the next pnb_execute on every rank, naming this one.
    status = pnb_publish_field(ctx, field, PNB_BORROW)
    call check(pnb_execute(ctx, 0.01d0 * s, int(s, c_int64_t)))
  end do
  status = pnb_last_step(ctx, stats)
  if (rank == 0) print '(a,i0,a,i0,a,i0,a)', 'ranks: ', ranks, '; last rendered step: cycle ', stats%cycle, ', ', &
                        stats%images, ' image(s)'
  ! Local: each rank flushes its own part; the ranks agree on the outcome before stopping alike.
  status = pnb_finalize(ctx)
  if (status /= PNB_OK) print '(a,i0,a,a)', 'rank ', rank, ': pnb_finalize: ', pnb_last_error_message(ctx)
  call MPI_Allreduce(MPI_IN_PLACE, status, 1, MPI_INTEGER, MPI_MAX, MPI_COMM_WORLD, ierr)
  call pnb_destroy(ctx)
  if (rank == 0 .and. status == PNB_OK) print '(a)', 'wrote ' // trim(outdir)
  call MPI_Finalize(ierr)
  if (status /= PNB_OK) stop 2

contains

  ! For the collective calls: a failure is every rank's (they agree on it), so each stops alike.
  subroutine check(st)
    integer(c_int), intent(in) :: st
    integer :: e
    if (st /= PNB_OK) then
      print '(a,i0,a,a)', 'rank ', rank, ': penumbra error: ', pnb_last_error_message(ctx)
      call MPI_Finalize(e)
      stop 2
    end if
  end subroutine

end program heat_fortran_mpi

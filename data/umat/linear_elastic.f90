! An isotropic linear elastic Abaqus UMAT (docs/umat.md), the example rendulic's tests drive:
! PROPS(1) = K (bulk modulus), PROPS(2) = G (shear modulus), optional PROPS(3) > 0 = the largest
! strain increment |DSTRAN| it accepts (a larger one gets PNEWDT = 0.5: the increment is cut).
! STATEV (any NSTATV) is bookkeeping the tests read back: STATEV(1) = largest accepted |DSTRAN|,
! STATEV(2) = STRAN(1) + DSTRAN(1), the total strain 11 after the increment.
! Build: gfortran -O2 -fPIC -shared linear_elastic.f90 -o linear_elastic.so
subroutine umat(stress, statev, ddsdde, sse, spd, scd, rpl, ddsddt, drplde, drpldt, stran, &
                dstran, time, dtime, temp, dtemp, predef, dpred, cmname, ndi, nshr, ntens, &
                nstatv, props, nprops, coords, drot, pnewdt, celent, dfgrd0, dfgrd1, noel, npt, &
                layer, kspt, kstep, kinc)
  implicit none
  character(len=80) :: cmname
  integer :: ndi, nshr, ntens, nstatv, nprops, noel, npt, layer, kspt, kstep, kinc
  double precision :: stress(ntens), statev(*), ddsdde(ntens, ntens), sse, spd, scd, rpl, &
                      ddsddt(ntens), drplde(ntens), drpldt, stran(ntens), dstran(ntens), &
                      time(2), dtime, temp, dtemp, predef(1), dpred(1), props(nprops), &
                      coords(3), drot(3, 3), pnewdt, celent, dfgrd0(3, 3), dfgrd1(3, 3)
  double precision :: bulk, shear, norm
  integer :: i, j

  bulk = props(1)
  shear = props(2)
  ! |DSTRAN| as the norm of the strain tensor (engineering shears halved).
  norm = sqrt(sum(dstran(1:ndi)**2) + 0.5d0 * sum(dstran(ndi + 1:ntens)**2))
  if (nprops >= 3) then
    if (props(3) > 0.d0 .and. norm > props(3)) then
      pnewdt = 0.5d0
      return
    end if
  end if

  ddsdde = 0.d0
  do i = 1, ndi
    do j = 1, ndi
      ddsdde(i, j) = bulk - 2.d0 * shear / 3.d0
    end do
    ddsdde(i, i) = bulk + 4.d0 * shear / 3.d0
  end do
  do i = ndi + 1, ntens
    ddsdde(i, i) = shear
  end do
  stress = stress + matmul(ddsdde, dstran)

  if (nstatv >= 1) statev(1) = max(statev(1), norm)
  if (nstatv >= 2) statev(2) = stran(1) + dstran(1)
end subroutine umat

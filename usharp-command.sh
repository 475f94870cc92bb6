# usharp external backend: test lcf, evaluation 14
echo run >> /work/main/build/test-scratch/extresume-count.txt; sh /work/main/test/ansys_standin.sh /work/main/build/gfortran_453B95A3D19CD205/app/usharp '/work/main/build/test-scratch'/extresume-internal.nml lcf

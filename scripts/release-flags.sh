# The release build's compiler flags, as the README's commands give them (SUNDIALS's Fortran
# modules; link-time optimisation, which inlines usharp's elementary functions into the
# model's rates). Sourced by the scripts in bench/ and scripts/, so that one line holds them.
FLAGS="-I/usr/include/sundials/fortran -flto"

@echo off
rem Runs one usharp APDL deck with ANSYS in batch mode, in the current folder (the folder
rem that holds the constants file the deck reads; the PRVAR listing is written there too).
rem
rem usage: run-ansys.bat DECK.inp
rem
rem Settings (edit here or set in the environment):
rem   ANSYS_EXE      the ANSYS Mechanical APDL executable
rem   ANS_USER_PATH  the folder of the user-programmable-features library built with the
rem                  usharp USERMAT (docs/user-guide.md, "a fit with ANSYS")
rem   ANSYS_OPTS     further options, e.g. a licence: -p ansys
if "%ANSYS_EXE%"=="" set "ANSYS_EXE=C:\Program Files\ANSYS Inc\v242\ansys\bin\winx64\MAPDL.exe"
if "%ANS_USER_PATH%"=="" set "ANS_USER_PATH=%USERPROFILE%\usharp-upf"
if "%~1"=="" (echo usage: run-ansys.bat DECK.inp 1>&2 & exit /b 2)
if not exist "%~1" (echo run-ansys.bat: cannot read %~1 1>&2 & exit /b 2)
rem -b batch, -np 1 one core (a single element), -i input, -o the solvers own listing
"%ANSYS_EXE%" -b -np 1 %ANSYS_OPTS% -i "%~1" -o ansys.out
exit /b %ERRORLEVEL%

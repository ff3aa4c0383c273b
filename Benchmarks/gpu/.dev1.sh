set -u
b=/tmp/b
mkdir -p $OUT
nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv > $OUT/gpu.txt 2>&1
cmake -S . -B $b -DMCVOL_CORE_ONLY=ON -DCMAKE_BUILD_TYPE=Release -DCMAKE_CUDA_COMPILER=$(command -v nvcc || echo /usr/local/cuda/bin/nvcc) > $OUT/configure.log 2>&1 || { tail -20 $OUT/configure.log; exit 1; }
start=$(date +%s)
timeout 520 cmake --build $b -j16 > $OUT/build.log 2>&1; echo "build rc=$? $(( $(date +%s) - start )) s"
tail -3 $OUT/build.log
left=$(( 570 - ($(date +%s) - start) ))
if [ $left -gt 30 ]; then (cd $b && timeout $left ctest -L cuda -j4 > $OUT/ctest-cuda.log 2>&1); echo "ctest rc=$?"; tail -12 $OUT/ctest-cuda.log; fi

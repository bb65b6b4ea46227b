# vio in a container, two stages on Debian 12 (bookworm):
#   build    the -dev packages and Python's plotting packages (tools/install_deps.sh build plot),
#            a Release build of `vio` alone, then tools/docker_runtime_files.sh collects what
#            runs: `vio`, OpenCV's image codecs (loaded by `vio` when first used), Python 3 with
#            numpy and matplotlib, and the shared libraries they load
#   runtime  the base image plus those files, config/ and tools/plot_sweep.py; `vio` is the
#            entrypoint. No compiler, no headers, no build tree, no tests.
#   docker build -t vio .          (another Debian 12 base image: --build-arg BASE=...)
#   docker run --rm -v /data/euroc:/data -v "$PWD/results":/results vio \
#     run --dataset=/data/V2_01_easy --output_dir=/results/V2_01_easy
# tools/docker_test.sh builds it and runs `vio simulate`, `vio run` and `vio sweep` inside.
ARG BASE=debian:bookworm

FROM ${BASE} AS build
RUN ls /usr/lib/x86_64-linux-gnu > /base-libs.txt
COPY tools/install_deps.sh /src/tools/install_deps.sh
RUN /src/tools/install_deps.sh build plot && rm -rf /var/lib/apt/lists/* \
 && for lib in libblas.so.3 liblapack.so.3; do \
      update-alternatives --set $lib-x86_64-linux-gnu /usr/lib/x86_64-linux-gnu/atlas/$lib; done
COPY . /src
RUN rm -rf /src/build \
 && BUILD_DIR=/build CMAKE_ARGS="-DVIO_BUILD_TESTS=OFF" /src/tools/build.sh --progress vio \
 && install -D -s /build/bin/vio /usr/local/bin/vio
RUN py=/usr/lib/python3/dist-packages \
 && /src/tools/docker_runtime_files.sh /runtime /base-libs.txt /usr/local/bin/vio /usr/bin/python3 \
      /usr/lib/x86_64-linux-gnu/libopencv_imgcodecs.so.4?? \
      /usr/lib/python3.11 $py/numpy $py/matplotlib $py/mpl_toolkits $py/PIL $py/kiwisolver $py/dateutil \
      $py/pyparsing $py/packaging $py/cycler.py $py/six.py /usr/share/matplotlib /etc/matplotlibrc \
 && install -D -m 755 /src/tools/plot_sweep.py /runtime/usr/local/share/vio/plot_sweep.py \
 && mkdir -p /runtime/opt/vio && cp -r /src/config /runtime/opt/vio/config

FROM ${BASE} AS runtime
COPY --from=build /runtime /
RUN ldconfig && vio --help > /dev/null \
 && python3 -c "import matplotlib; matplotlib.use('Agg'); import matplotlib.pyplot, numpy"
WORKDIR /work
ENTRYPOINT ["vio"]
CMD ["--help"]

# vio in a container: Debian 12 (bookworm) with the same install script as the
# README and CI, a Release build, and `vio` as the entrypoint.
#   docker build -t vio .
#   docker run --rm -v /data/euroc:/data -v "$PWD/results":/results vio \
#     run --dataset=/data/V2_01_easy --output_dir=/results/V2_01_easy
FROM debian:bookworm

COPY tools/install_deps.sh /opt/vio/tools/install_deps.sh
RUN /opt/vio/tools/install_deps.sh && rm -rf /var/lib/apt/lists/*

COPY . /opt/vio
RUN cd /opt/vio && rm -rf build && BUILD_DIR=/opt/vio/build tools/build.sh \
 && ln -s /opt/vio/build/bin/vio /usr/local/bin/vio

WORKDIR /work
ENTRYPOINT ["vio"]
CMD ["--help"]

#!/usr/bin/env bash
# Installs everything lodbake needs on a Debian (bookworm) machine: compilers and CMake (GCC, and
# Clang with libclang-rt-14-dev, its sanitizer and libFuzzer runtimes, which --no-install-recommends
# would leave out, for the sanitizer job and the fuzzers), the libraries (tinygltf, Draco,
# OpenImageIO, oneTBB, GoogleTest, nlohmann-json), the tools the tests and benchmarks run (Draco
# CLI, meshoptimizer, Open3D for ../shared/eval, Universal Ctags for the function-length check,
# Chromium for the browser tests) and the npm packages of scripts/node (Khronos glTF-Validator,
# Babylon.js, three.js). Safe to run again: it installs only what is missing.
set -euo pipefail
cd "$(dirname "$0")/.."

packages=(
    build-essential cmake ninja-build pkg-config git
    clang libclang-rt-14-dev
    libtinygltf-dev nlohmann-json3-dev
    libdraco-dev draco
    libopenimageio-dev openimageio-tools
    libtbb-dev
    libgtest-dev googletest
    libmeshoptimizer-dev
    python3 python3-numpy python3-open3d python3-jsonschema
    universal-ctags
    # lodview and its headless test: GLFW, libepoxy, Mesa's GL with the llvmpipe driver, Xvfb, stb_image.
    libglfw3-dev libepoxy-dev libgl-dev libgl1-mesa-dri xvfb xauth libstb-dev
    # The range-scan merge's screened Poisson reconstruction (baker/src/reconstruct/, liblodbake_open3d).
    libopen3d-dev
    # The browser tests (tests/browser): headless Chromium draws packs with Babylon.js and three.js.
    chromium
    # The cluster LOD builder's graph partition (baker/src/cluster/).
    libmetis-dev
)
# Node.js: machines of this kind ship it (with npm bundled); Debian's own npm package conflicts with
# such a build, so only ask apt for node and npm when the commands are missing.
command -v node >/dev/null 2>&1 || packages+=(nodejs)
command -v npm >/dev/null 2>&1 || packages+=(npm)

missing=()
for p in "${packages[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
    sudo_cmd=()
    if [ "$(id -u)" -ne 0 ]; then sudo_cmd=(sudo); fi
    echo "installing Debian packages: ${missing[*]}"
    "${sudo_cmd[@]}" apt-get update -qq
    DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# Node tools used by the tests (versions pinned by scripts/node/package-lock.json): installed when a
# dependency of scripts/node/package.json is missing or at another version.
if ! node -e 'const p = require("./scripts/node/package.json");
    for (const [name, version] of Object.entries(p.dependencies))
        if (require(`./scripts/node/node_modules/${name}/package.json`).version !== version) process.exit(1);' 2>/dev/null; then
    echo "installing npm packages for the tests (scripts/node)"
    (cd scripts/node && npm ci --no-audit --no-fund --loglevel=error)
fi
# gltfpack (pinned by scripts/node-bench/package-lock.json): the benchmarks' anchor, and the
# EXT_meshopt_compression files WebPackTest opens (it skips without it); glTF-Transform's CLI, the
# other writer whose meshopt and quantize files WebPackTest opens.
if [ ! -x scripts/node-bench/node_modules/.bin/gltfpack ] || [ ! -x scripts/node-bench/node_modules/.bin/gltf-transform ]; then
    echo "installing npm packages for the benchmarks and the web-pack tests (scripts/node-bench)"
    (cd scripts/node-bench && npm ci --no-audit --no-fund --loglevel=error)
fi

# ctcsim - build, test and benchmark.
#
#   make deps-run  install the Debian packages that building and running the service and its
#                page need (as root), or print the command to run as root
#   make deps    the same for everything make test needs (deps-run plus the test stack)
#   make         build the library, the ctcsim command line and the ctcsim-server service
#   make web     assemble the page into build/web (web/ plus uPlot from npm ci)
#   make run     deps-run, uPlot from npm, build, and start the service on 127.0.0.1:8080 with
#                its database in ./ctcsim.db (RUN_ARGS adds flags)
#   make test    deps and both npm installs first (the network steps, so that they fail fast),
#                then build and run the unit tests, then again under AddressSanitizer + UBSan
#                (built with SAN_CC); each test binary has a time limit (tests/run.sh)
#   make test-container  the README's commands, literally, in a pristine Debian bookworm
#                (tests/container.sh; as root; slow, not part of make test)
#   make bench   build for this machine, run the unit tests in that build, then the benchmarks
#   make install install the library (libctcsim.a, include/ctcsim/, ctcsim.pc), the ctcsim and
#                ctcsim-server programs, and the page and API files (share/ctcsim/) under
#                PREFIX (/usr/local), staged under DESTDIR when set; make uninstall removes them
#   make fuzz    build the libFuzzer harnesses of the job parser (fuzz/) with SAN_CC and run each
#                for FUZZ_TIME seconds (60); fails on a crash, leak, timeout or broken contract and
#                leaves the reproducer in build/fuzz/ (fuzz/README.md; not part of make test)
#   make clean   remove build/
#
# Overridable: CC, SAN_CC, OPT (optimisation flags), BUILD (output folder), EXTRA_CFLAGS,
# EXTRA_LDFLAGS. Builds run one compile per core (NPROC) unless the command line gives -j.

CC ?= cc
# -O3 without gcc's vectoriser, which slows the library's 3- and 6-vector kernels (they use simd.h
# where vectors pay): bench/NOTEBOOK.md, "Before that: the sequential order", change 5. The
# default build stays portable (baseline x86-64), and its hot kernels carry AVX2 + FMA and
# AVX-512 copies chosen at load time (src/core/clones.h); -ffp-contract=fast lets those copies
# fuse a * b + c, which gcc leaves off in ISO C mode (-std=c11): bench/NOTEBOOK.md, "The portable
# build (issue 26)"
OPT_DEFAULT := -O3 -fno-tree-vectorize -ffp-contract=fast
# make bench builds for this machine: its instruction set (with fused multiply-adds, where it has
# them); the figures: bench/NOTEBOOK.md, "Latest", change 1. The unit tests pass in either build,
# and make bench runs them in its own first.
OPT_BENCH := $(OPT_DEFAULT) -march=native -DNDEBUG
OPT ?= $(OPT_DEFAULT)
BUILD ?= build
SANITIZE ?=
NPROC := $(shell nproc 2>/dev/null || echo 1)
JOBS = $(if $(filter -j% j%,$(MAKEFLAGS)),,-j$(NPROC))
# The sanitizer pass's compiler. Criterion forks each test's worker from a runner that has other
# threads (BoxFort's child pump, nanomsg's I/O thread), and the worker allocates before it execs.
# GCC 12's ASan runtime (libasan 8) takes no lock around fork(), so a worker forked while another
# thread holds an allocator lock can wait for it forever. LLVM 18 and later lock the allocator and
# the stack depot around fork (pthread_atfork in the ASan runtime), so the pass is built with
# Debian's clang-19. The plain pass uses glibc's malloc, which is fork-safe.
SAN_CC ?= clang-19

WARN := -Wall -Wextra -Wshadow -Wstrict-prototypes -Werror
# src/: the public headers in src/include, the sources by pipeline stage in the other folders
# (each stage's private headers beside its sources); every folder is on the include path
SRC_DIRS := $(sort $(dir $(wildcard src/*/*)))
CFLAGS := -std=c11 $(WARN) $(OPT) -g -D_POSIX_C_SOURCE=200809L $(patsubst %/,-I%,$(SRC_DIRS)) \
	$(EXTRA_CFLAGS)
LDFLAGS := $(EXTRA_LDFLAGS)
LDLIBS := -lcjson -lsundials_cvode -lsundials_nvecserial -lsundials_sunmatrixdense \
	-lsundials_sunlinsoldense -llapacke -llapack -lblas -lm -pthread
ifeq ($(SANITIZE),1)
CFLAGS += -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=all
LDFLAGS += -fsanitize=address,undefined
endif

# Debian packages that building and running the service and its page need (ca-certificates: npm
# checks the registry's certificate against them); and those the tests add: Criterion, clang-19
# and its sanitizer runtime (the ASan + UBSan pass), Chromium (the browser tests), the sqlite3
# command (the crash test's integrity check), curl and jq (the README's service examples). Both
# sets also need node (>= 18) and npm for uPlot and playwright-core: Debian's nodejs and npm are
# installed when the machine has no node.
RUN_PACKAGES := gcc make libc6-dev libcjson-dev liblapacke-dev libsundials-dev libmicrohttpd-dev \
	libsqlite3-dev libxml2-dev libpq-dev zlib1g-dev ca-certificates
TEST_PACKAGES := libcriterion-dev clang-19 libclang-rt-19-dev chromium sqlite3 curl jq postgresql
DEB_PACKAGES := $(RUN_PACKAGES) $(TEST_PACKAGES)
# npm trusts the system's CA bundle too (a TLS-inspecting proxy whose CA is in the system store),
# unless NODE_EXTRA_CA_CERTS is set already
SYSTEM_CA := /etc/ssl/certs/ca-certificates.crt
NPM_CA = $(if $(NODE_EXTRA_CA_CERTS),,\
	$(if $(wildcard $(SYSTEM_CA)),NODE_EXTRA_CA_CERTS=$(SYSTEM_CA)))
NPM_CI = $(NPM_CA) npm ci --no-audit --no-fund --loglevel=error
BENCH_PACKAGES := wrk curl libmujoco-dev libdart-dev

LIB_SRC := $(wildcard src/*/*.c)
LIB_OBJ := $(LIB_SRC:src/%.c=$(BUILD)/obj/%.o)
LIB := $(BUILD)/libctcsim.a
# server/: the job format, presets and outputs shared by the command line and the service, and
# the programs' mains
MAINS := server/cli.c server/main.c
APP_SRC := $(filter-out $(MAINS),$(wildcard server/*.c))
APP_OBJ := $(APP_SRC:server/%.c=$(BUILD)/obj/server/%.o)
APP_LIB := $(BUILD)/libctcapp.a
CLI := $(BUILD)/ctcsim
SERVER := $(BUILD)/ctcsim-server
# libxml2 reads URDF robot descriptions (server/urdf.c): the C library made for XML, with the line
# numbers that its messages name
XML_CFLAGS := $(shell pkg-config --cflags libxml-2.0 2>/dev/null || echo -I/usr/include/libxml2)
XML_LIBS := $(shell pkg-config --libs libxml-2.0 2>/dev/null || echo -lxml2)
# libpq talks to PostgreSQL (server/store_pg.c, --db postgres://...)
PQ_CFLAGS := $(shell pkg-config --cflags libpq 2>/dev/null || echo -I/usr/include/postgresql)
PQ_LIBS := $(shell pkg-config --libs libpq 2>/dev/null || echo -lpq)
# zlib compresses large replies for clients that accept gzip (server/http_gzip.c): the format's
# reference implementation, already on every Debian system
SERVER_LDLIBS := -lmicrohttpd -lsqlite3 $(XML_LIBS) $(PQ_LIBS) -lz
# the served page: web/ plus uPlot's files from npm ci (nothing from node_modules is committed)
WEB_OUT := build/web
WEB_NPM := build/web-npm
WEB_SRC := $(filter-out web/package.json web/package-lock.json web/README.md,$(wildcard web/*))
TEST_SRC := $(wildcard tests/unit/test_*.c)
TEST_BIN := $(TEST_SRC:tests/unit/%.c=$(BUILD)/tests/%)
SUPPORT_SRC := $(wildcard tests/support/*.c)
SUPPORT_OBJ := $(SUPPORT_SRC:tests/support/%.c=$(BUILD)/obj/support/%.o)
BENCH_SRC := $(wildcard bench/*.c)
BENCH_BIN := $(BENCH_SRC:bench/%.c=$(BUILD)/bench/%)
# fuzz/: the harnesses, each built two ways (fuzz/README.md): NAME_fuzzer with libFuzzer (make
# fuzz, in its own build folder FUZZ_BUILD) and NAME_seeds with seed_driver.c (make check runs the
# seeds through it, in the suite's build); and job_dict, the dictionary's generator
FUZZ_NAMES := fuzz_job fuzz_merge
FUZZ_SEEDS := $(FUZZ_NAMES:%=$(BUILD)/fuzzers/%_seeds) $(BUILD)/fuzzers/job_dict
FUZZ_BUILD := build/fuzz
FUZZ_TIME ?= 60

.PHONY: all deps deps-run bench-deps install-packages npm-deps web run test test-container check \
	check-build check-asan check-fuzz-seeds fuzz fuzz-dict bench clean install uninstall FORCE
.DELETE_ON_ERROR:
.SECONDARY:

all: $(LIB) $(CLI) $(SERVER)

# The compiler and flags that a build folder's objects were made with. Everything compiled
# depends on this file, which is rewritten only when they change: a build into the same folder
# with other flags (OPT, SANITIZE, EXTRA_CFLAGS) recompiles instead of reusing objects made with
# the old ones.
FLAGS_STAMP := $(BUILD)/flags
BUILD_FLAGS := $(CC) $(CFLAGS) $(LDFLAGS)
$(FLAGS_STAMP): FORCE
	@mkdir -p $(@D)
	@echo '$(BUILD_FLAGS)' | cmp -s - $@ || echo '$(BUILD_FLAGS)' > $@

$(BUILD)/obj/%.o: src/%.c $(FLAGS_STAMP)
	@mkdir -p $(@D)
	$(CC) $(CFLAGS) -MMD -MP -c $< -o $@

$(BUILD)/obj/server/%.o: server/%.c $(FLAGS_STAMP)
	@mkdir -p $(@D)
	$(CC) $(CFLAGS) $(XML_CFLAGS) $(PQ_CFLAGS) -Iserver -MMD -MP -c $< -o $@

$(BUILD)/obj/support/%.o: tests/support/%.c $(FLAGS_STAMP)
	@mkdir -p $(@D)
	$(CC) $(CFLAGS) -Itests/support -MMD -MP -c $< -o $@

$(LIB): $(LIB_OBJ)
	@mkdir -p $(@D)
	rm -f $@
	ar rcs $@ $^

$(APP_LIB): $(APP_OBJ)
	@mkdir -p $(@D)
	rm -f $@
	ar rcs $@ $^

$(CLI): $(BUILD)/obj/server/cli.o $(APP_LIB) $(LIB)
	$(CC) $^ -o $@ $(LDFLAGS) $(SERVER_LDLIBS) $(LDLIBS)

$(SERVER): $(BUILD)/obj/server/main.o $(APP_LIB) $(LIB)
	$(CC) $^ -o $@ $(LDFLAGS) $(SERVER_LDLIBS) $(LDLIBS)

$(BUILD)/tests/%: tests/unit/%.c $(SUPPORT_OBJ) $(APP_LIB) $(LIB) $(FLAGS_STAMP)
	@mkdir -p $(@D)
	$(CC) $(CFLAGS) -Itests/support -Iserver -MMD -MP $< $(SUPPORT_OBJ) $(APP_LIB) $(LIB) -o $@ \
		$(LDFLAGS) -lcriterion $(SERVER_LDLIBS) $(LDLIBS)

# benchmarks also link SUNDIALS ARKODE, to measure it against the in-house explicit steppers;
# bench_mujoco alone links MuJoCo (libmujoco-dev) and DART (libdart-dev, through the C++ shim
# bench/dart_peer.cpp), to measure ctcsim against them. DART is compiled in where pkg-config
# finds it; otherwise the shim says so and bench_mujoco skips DART (make bench-deps installs it).
BENCH_LDLIBS := -lsundials_arkode
BENCH_OBJ :=
DART_FOUND := $(shell pkg-config --exists dart 2>/dev/null && echo 1)
DART_CXXFLAGS := $(if $(DART_FOUND),-DCTC_HAVE_DART \
	$(filter-out -std=%,$(shell pkg-config --cflags dart 2>/dev/null)))
DART_LIBS := $(if $(DART_FOUND),$(shell pkg-config --libs dart 2>/dev/null))
# the shim is compiled for the target Debian's DART was (no -march): Eigen aligns its fixed-size
# members by the instruction set, so DART's structures must have the layout its library has
BENCH_CXXFLAGS := -std=c++17 -Wall -Wextra -Werror $(filter-out -march=%,$(OPT)) -g -Isrc/include \
	$(DART_CXXFLAGS)
$(BUILD)/obj/bench/%.o: bench/%.cpp $(FLAGS_STAMP)
	@mkdir -p $(@D)
	$(CXX) $(BENCH_CXXFLAGS) -MMD -MP -c $< -o $@
$(BUILD)/bench/bench_mujoco: BENCH_OBJ := $(BUILD)/obj/bench/dart_peer.o
$(BUILD)/bench/bench_mujoco: BENCH_LDLIBS += -lmujoco $(DART_LIBS) -lstdc++
$(BUILD)/bench/bench_mujoco: $(BUILD)/obj/bench/dart_peer.o
$(BUILD)/bench/%: bench/%.c $(SUPPORT_OBJ) $(APP_LIB) $(LIB) $(FLAGS_STAMP)
	@mkdir -p $(@D)
	$(CC) $(CFLAGS) -Itests/support -Iserver -MMD -MP $< $(BENCH_OBJ) $(SUPPORT_OBJ) $(APP_LIB) \
		$(LIB) -o $@ $(LDFLAGS) $(BENCH_LDLIBS) $(SERVER_LDLIBS) $(LDLIBS)

$(BUILD)/fuzzers/%_seeds: fuzz/%.c fuzz/seed_driver.c $(APP_LIB) $(LIB) $(FLAGS_STAMP)
	@mkdir -p $(@D)
	$(CC) $(CFLAGS) -Iserver $< fuzz/seed_driver.c $(APP_LIB) $(LIB) -o $@ $(LDFLAGS) \
		$(SERVER_LDLIBS) $(LDLIBS)

$(BUILD)/fuzzers/%_fuzzer: fuzz/%.c $(APP_LIB) $(LIB) $(FLAGS_STAMP)
	@mkdir -p $(@D)
	$(CC) $(CFLAGS) -Iserver -fsanitize=fuzzer $< $(APP_LIB) $(LIB) -o $@ $(LDFLAGS) \
		-fsanitize=fuzzer $(SERVER_LDLIBS) $(LDLIBS)

$(BUILD)/fuzzers/job_dict: fuzz/job_dict.c $(APP_LIB) $(LIB) $(FLAGS_STAMP)
	@mkdir -p $(@D)
	$(CC) $(CFLAGS) -Iserver $< $(APP_LIB) $(LIB) -o $@ $(LDFLAGS) $(SERVER_LDLIBS) $(LDLIBS)

# install what is missing: apt-get as root (updating the package lists first when there are
# none, or when a package is not found), otherwise print the command to run as root and fail
deps:
	@$(MAKE) --no-print-directory install-packages PACKAGES="$(DEB_PACKAGES)" CHECK_NODE=1

deps-run:
	@$(MAKE) --no-print-directory install-packages PACKAGES="$(RUN_PACKAGES)" CHECK_NODE=1

# the benchmarks also need wrk and curl (bench/bench_server.sh), MuJoCo and DART (bench_mujoco)
bench-deps: deps
	@$(MAKE) --no-print-directory install-packages PACKAGES="$(BENCH_PACKAGES)"

install-packages:
	@missing=""; \
	for p in $(PACKAGES); do \
		dpkg-query -W -f='$${Status}' $$p 2>/dev/null | grep -q "install ok installed" \
			|| missing="$$missing $$p"; \
	done; \
	if [ -n "$(CHECK_NODE)" ]; then \
		command -v node >/dev/null 2>&1 || missing="$$missing nodejs"; \
		command -v npm >/dev/null 2>&1 || missing="$$missing npm"; \
	fi; \
	[ -z "$$missing" ] && exit 0; \
	if [ "$$(id -u)" != 0 ]; then \
		cmd="apt-get update && apt-get install -y --no-install-recommends$$missing"; \
		echo "ctcsim needs these Debian packages:$$missing"; \
		echo "install them as root:"; \
		echo "    $$cmd"; \
		echo "for example with su (root's password):"; \
		echo "    su -c '$$cmd'"; \
		echo "or, where sudo is installed and allows you:"; \
		echo "    sudo sh -c '$$cmd'"; \
		exit 1; \
	fi; \
	export DEBIAN_FRONTEND=noninteractive; \
	if ! ls /var/lib/apt/lists/*_Packages* >/dev/null 2>&1; then apt-get update; fi; \
	apt-get install -y --no-install-recommends $$missing \
		|| { apt-get update && apt-get install -y --no-install-recommends $$missing; }

web: $(WEB_OUT)/.stamp

$(WEB_NPM)/node_modules/.package-lock.json: web/package.json web/package-lock.json
	@mkdir -p $(WEB_NPM)
	cp web/package.json web/package-lock.json $(WEB_NPM)/
	cd $(WEB_NPM) && $(NPM_CI)

$(WEB_OUT)/.stamp: $(WEB_SRC) $(WEB_NPM)/node_modules/.package-lock.json
	@rm -rf $(WEB_OUT) && mkdir -p $(WEB_OUT)/vendor
	cp $(WEB_SRC) $(WEB_OUT)/
	cp $(WEB_NPM)/node_modules/uplot/dist/uPlot.esm.js \
		$(WEB_NPM)/node_modules/uplot/dist/uPlot.min.css $(WEB_OUT)/vendor/
	@touch $@

tests/web/node_modules/.package-lock.json: tests/web/package.json tests/web/package-lock.json
	cd tests/web && $(NPM_CI)

# builds everything the suite needs, in parallel, then runs it as built in $(BUILD)
CHECK_DEPS := $(TEST_BIN) $(CLI) $(SERVER) $(FUZZ_SEEDS) web tests/web/node_modules/.package-lock.json
check-build: $(CHECK_DEPS)

check:
	@$(MAKE) --no-print-directory $(JOBS) check-build
	@sh tests/run.sh $(TEST_BIN)
	@$(MAKE) --no-print-directory check-fuzz-seeds
	@CTCSIM=$(CLI) sh tests/cli/run.sh
	@CTCSIM=$(CLI) sh tests/cli/readme.sh
	@MAKE="$(MAKE)" CC="$(CC)" EXAMPLE_FLAGS="$(LDFLAGS)" sh tests/cli/install.sh
	@CTCSIM=$(CLI) CTCSIM_SERVER=$(SERVER) sh tests/api/run.sh
	@CTCSIM_SERVER=$(SERVER) WEB_ROOT=$(WEB_OUT) API_DIR=api sh tests/web/run.sh

# the harnesses cannot rot: each runs its seeds once (a few seconds), and the committed dictionary
# is what the format's tables make now
check-fuzz-seeds: $(FUZZ_SEEDS) $(CLI)
	@sh fuzz/corpus.sh $(CLI) $(BUILD)/fuzzers/seeds >/dev/null
	@for h in $(FUZZ_NAMES); do $(BUILD)/fuzzers/$${h}_seeds $(BUILD)/fuzzers/seeds/$$h || exit 1; done
	@$(BUILD)/fuzzers/job_dict | diff -u fuzz/job.dict - \
		|| { echo "fuzz/job.dict is stale: make fuzz-dict rewrites it"; exit 1; }

fuzz-dict: $(BUILD)/fuzzers/job_dict
	$(BUILD)/fuzzers/job_dict >fuzz/job.dict

# libFuzzer needs the code under test instrumented for coverage (-fsanitize=fuzzer-no-link) and
# its own main: a build folder of its own, with ASan + UBSan
fuzz:
	@$(MAKE) --no-print-directory $(JOBS) BUILD=$(FUZZ_BUILD) SANITIZE=1 OPT=-O1 CC=$(SAN_CC) \
		EXTRA_CFLAGS=-fsanitize=fuzzer-no-link \
		$(FUZZ_NAMES:%=$(FUZZ_BUILD)/fuzzers/%_fuzzer) $(FUZZ_BUILD)/ctcsim
	@FUZZ_TIME=$(FUZZ_TIME) sh fuzz/run.sh $(FUZZ_BUILD) $(FUZZ_NAMES)

check-asan:
	@$(MAKE) --no-print-directory BUILD=$(BUILD)/asan SANITIZE=1 OPT=-O1 CC=$(SAN_CC) check

# the network steps (both npm installs) before the long builds, so that they fail fast
NPM_STAMPS := $(WEB_NPM)/node_modules/.package-lock.json tests/web/node_modules/.package-lock.json
npm-deps: $(NPM_STAMPS)

test: deps
	@$(MAKE) --no-print-directory npm-deps
	@$(MAKE) --no-print-directory check
	@echo "== again under AddressSanitizer + UndefinedBehaviorSanitizer"
	@$(MAKE) --no-print-directory check-asan

run: deps-run
	@$(MAKE) --no-print-directory $(WEB_NPM)/node_modules/.package-lock.json
	@$(MAKE) --no-print-directory $(JOBS) $(SERVER) web
	$(SERVER) --web $(WEB_OUT) $(RUN_ARGS)

# the unit tests run in the benchmarks' build first, so that the arithmetic they time (fused
# where the machine has FMA) is the tested arithmetic
bench: bench-deps
	@$(MAKE) --no-print-directory $(JOBS) BUILD=$(BUILD)/bench-o3 OPT="$(OPT_BENCH)" \
		$(BENCH_SRC:bench/%.c=$(BUILD)/bench-o3/bench/%) $(BUILD)/bench-o3/ctcsim-server \
		$(TEST_SRC:tests/unit/%.c=$(BUILD)/bench-o3/tests/%)
	@echo "== the unit tests, built as the benchmarks are"
	@sh tests/run.sh $(TEST_SRC:tests/unit/%.c=$(BUILD)/bench-o3/tests/%)
	@for b in $(BENCH_SRC:bench/%.c=$(BUILD)/bench-o3/bench/%); do echo "== $$b"; $$b || exit 1; done
	@echo "== bench/bench_server.sh"
	@sh bench/bench_server.sh $(BUILD)/bench-o3/ctcsim-server

# make install: what a program of one's own needs to use the library (examples/pendulum.c builds
# with `pkg-config --cflags --libs ctcsim`), the two programs, and what ctcsim-server serves
# (--web PREFIX/share/ctcsim/web --api PREFIX/share/ctcsim/api). The public headers are those
# ctc.h and sim.h reach, with the controllers', trajectories', integrators' and oracle's
# (src/include); they include one another by bare name, so they sit together in include/ctcsim/.
# The library is static: ctcsim.pc's Libs carry the libraries it links.
PREFIX ?= /usr/local
DESTDIR ?=
VERSION := $(shell sed -n 's/^\#define CTCSIM_VERSION "\(.*\)"/\1/p' server/routes.h)
PUBLIC_HEADERS := $(wildcard src/include/*.h)
INSTALL_DIRS := bin lib lib/pkgconfig include/ctcsim share/ctcsim/web share/ctcsim/web/vendor \
	share/ctcsim/api share/ctcsim/api/examples share/ctcsim/api/examples/families

install: $(LIB) $(CLI) $(SERVER) web
	@for d in $(INSTALL_DIRS); do install -d "$(DESTDIR)$(PREFIX)/$$d" || exit 1; done
	install -m 644 $(LIB) "$(DESTDIR)$(PREFIX)/lib/libctcsim.a"
	install -m 644 $(PUBLIC_HEADERS) "$(DESTDIR)$(PREFIX)/include/ctcsim/"
	install -m 755 $(CLI) $(SERVER) "$(DESTDIR)$(PREFIX)/bin/"
	install -m 644 $(filter-out $(WEB_OUT)/vendor $(WEB_OUT)/.stamp,$(wildcard $(WEB_OUT)/*)) \
		"$(DESTDIR)$(PREFIX)/share/ctcsim/web/"
	install -m 644 $(wildcard $(WEB_OUT)/vendor/*) "$(DESTDIR)$(PREFIX)/share/ctcsim/web/vendor/"
	install -m 644 api/openapi.yaml api/job.schema.json "$(DESTDIR)$(PREFIX)/share/ctcsim/api/"
	install -m 644 $(wildcard api/examples/*.json) "$(DESTDIR)$(PREFIX)/share/ctcsim/api/examples/"
	install -m 644 $(wildcard api/examples/families/*.json) \
		"$(DESTDIR)$(PREFIX)/share/ctcsim/api/examples/families/"
	printf '%s\n' 'prefix=$(PREFIX)' 'exec_prefix=$${prefix}' 'libdir=$${exec_prefix}/lib' \
		'includedir=$${prefix}/include' '' 'Name: ctcsim' \
		'Description: computed torque control of multibody chains with the GDCA and iGDCA' \
		'Version: $(VERSION)' 'Cflags: -I$${includedir}' \
		'Libs: -L$${libdir} -lctcsim $(filter-out -lcjson,$(LDLIBS))' \
		> "$(DESTDIR)$(PREFIX)/lib/pkgconfig/ctcsim.pc"

uninstall:
	rm -f "$(DESTDIR)$(PREFIX)/lib/libctcsim.a" "$(DESTDIR)$(PREFIX)/lib/pkgconfig/ctcsim.pc" \
		"$(DESTDIR)$(PREFIX)/bin/ctcsim" "$(DESTDIR)$(PREFIX)/bin/ctcsim-server"
	rm -f $(PUBLIC_HEADERS:src/include/%="$(DESTDIR)$(PREFIX)/include/ctcsim/%")
	rm -rf "$(DESTDIR)$(PREFIX)/share/ctcsim"
	-rmdir "$(DESTDIR)$(PREFIX)/include/ctcsim" 2>/dev/null

# a pristine bookworm (Docker where a daemon answers, else debootstrap + chroot under
# build/container, as root), a fresh clone of HEAD, the README's "install first" line, make run
# (started, /api/health, stopped) and make test; prints each phase's time and what it installed
test-container:
	bash tests/container.sh

clean:
	rm -rf $(BUILD)

-include $(LIB_OBJ:.o=.d) $(APP_OBJ:.o=.d) $(MAINS:server/%.c=$(BUILD)/obj/server/%.d) \
	$(SUPPORT_OBJ:.o=.d) $(TEST_BIN:=.d) $(BENCH_BIN:=.d) $(BUILD)/obj/bench/dart_peer.d

# ctcsim - build, test and benchmark.
#
#   make deps    install missing Debian packages (as root), or print the apt-get line to run
#   make         build the library, the ctcsim command line and the ctcsim-server service
#   make run     install what is missing (as root), build, and start the service on
#                127.0.0.1:8080 with its database in ./ctcsim.db (RUN_ARGS adds flags)
#   make test    build and run the unit tests, then again under AddressSanitizer + UBSan
#   make bench   build with optimisation and run the benchmarks
#   make clean   remove build/
#
# Overridable: CC, OPT (optimisation flags), BUILD (output folder), EXTRA_CFLAGS, EXTRA_LDFLAGS.

CC ?= cc
OPT ?= -O2
BUILD ?= build
SANITIZE ?=

WARN := -Wall -Wextra -Wshadow -Wstrict-prototypes -Werror
CFLAGS := -std=c11 $(WARN) $(OPT) -g -D_POSIX_C_SOURCE=200809L -Isrc $(EXTRA_CFLAGS)
LDFLAGS := $(EXTRA_LDFLAGS)
LDLIBS := -lcjson -lsundials_cvode -lsundials_nvecserial -lsundials_sunmatrixdense \
	-lsundials_sunlinsoldense -llapacke -llapack -lblas -lm
ifeq ($(SANITIZE),1)
CFLAGS += -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=all
LDFLAGS += -fsanitize=address,undefined
endif

# Debian packages the build and the tests need
DEB_PACKAGES := gcc make libc6-dev libcriterion-dev libcjson-dev liblapacke-dev libsundials-dev \
	libmicrohttpd-dev libsqlite3-dev
# the API tests run on Node's built-in test runner (node >= 18); Debian's nodejs when none
NODE_PACKAGE := nodejs
BENCH_PACKAGES := wrk curl

LIB_SRC := $(wildcard src/*.c)
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
SERVER_LDLIBS := -lmicrohttpd -lsqlite3 -lpthread
TEST_SRC := $(wildcard tests/unit/test_*.c)
TEST_BIN := $(TEST_SRC:tests/unit/%.c=$(BUILD)/tests/%)
SUPPORT_SRC := $(wildcard tests/support/*.c)
SUPPORT_OBJ := $(SUPPORT_SRC:tests/support/%.c=$(BUILD)/obj/support/%.o)
BENCH_SRC := $(wildcard bench/*.c)
BENCH_BIN := $(BENCH_SRC:bench/%.c=$(BUILD)/bench/%)

.PHONY: all deps bench-deps install-packages run test check check-asan bench clean
.DELETE_ON_ERROR:
.SECONDARY:

all: $(LIB) $(CLI) $(SERVER)

$(BUILD)/obj/%.o: src/%.c
	@mkdir -p $(@D)
	$(CC) $(CFLAGS) -MMD -MP -c $< -o $@

$(BUILD)/obj/server/%.o: server/%.c
	@mkdir -p $(@D)
	$(CC) $(CFLAGS) -Iserver -MMD -MP -c $< -o $@

$(BUILD)/obj/support/%.o: tests/support/%.c
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

$(BUILD)/tests/%: tests/unit/%.c $(SUPPORT_OBJ) $(APP_LIB) $(LIB)
	@mkdir -p $(@D)
	$(CC) $(CFLAGS) -Itests/support -Iserver -MMD -MP $< $(SUPPORT_OBJ) $(APP_LIB) $(LIB) -o $@ \
		$(LDFLAGS) -lcriterion $(SERVER_LDLIBS) $(LDLIBS)

# benchmarks also link SUNDIALS ARKODE, to measure it against the in-house explicit steppers
$(BUILD)/bench/%: bench/%.c $(SUPPORT_OBJ) $(APP_LIB) $(LIB)
	@mkdir -p $(@D)
	$(CC) $(CFLAGS) -Itests/support -Iserver -MMD -MP $< $(SUPPORT_OBJ) $(APP_LIB) $(LIB) -o $@ \
		$(LDFLAGS) -lsundials_arkode $(SERVER_LDLIBS) $(LDLIBS)

# installs what is missing: apt-get as root (updating the package lists first when there are
# none, or when a package is not found), otherwise prints the command to run and fails
deps:
	@$(MAKE) --no-print-directory install-packages PACKAGES="$(DEB_PACKAGES)" CHECK_NODE=1

# the benchmarks also need wrk and curl (bench/bench_server.sh)
bench-deps: deps
	@$(MAKE) --no-print-directory install-packages PACKAGES="$(BENCH_PACKAGES)"

install-packages:
	@missing=""; \
	for p in $(PACKAGES); do \
		dpkg-query -W -f='$${Status}' $$p 2>/dev/null | grep -q "install ok installed" \
			|| missing="$$missing $$p"; \
	done; \
	if [ -n "$(CHECK_NODE)" ]; then \
		command -v node >/dev/null 2>&1 || missing="$$missing $(NODE_PACKAGE)"; \
	fi; \
	[ -z "$$missing" ] && exit 0; \
	if [ "$$(id -u)" != 0 ]; then \
		echo "ctcsim needs these Debian packages:$$missing"; \
		echo "install them with: sudo apt-get install -y$$missing"; \
		exit 1; \
	fi; \
	export DEBIAN_FRONTEND=noninteractive; \
	if ! ls /var/lib/apt/lists/*_Packages* >/dev/null 2>&1; then apt-get update; fi; \
	apt-get install -y --no-install-recommends $$missing \
		|| { apt-get update && apt-get install -y --no-install-recommends $$missing; }

# runs the suite as built in $(BUILD)
check: $(TEST_BIN) $(CLI) $(SERVER)
	@sh tests/run.sh $(TEST_BIN)
	@CTCSIM=$(CLI) sh tests/cli/run.sh
	@CTCSIM=$(CLI) CTCSIM_SERVER=$(SERVER) sh tests/api/run.sh

check-asan:
	@$(MAKE) --no-print-directory BUILD=$(BUILD)/asan SANITIZE=1 OPT=-O1 check

test: deps
	@$(MAKE) --no-print-directory check
	@echo "== again under AddressSanitizer + UndefinedBehaviorSanitizer"
	@$(MAKE) --no-print-directory check-asan

run: deps
	@$(MAKE) --no-print-directory $(SERVER)
	$(SERVER) $(RUN_ARGS)

bench: bench-deps
	@$(MAKE) --no-print-directory BUILD=$(BUILD)/bench-o3 OPT="-O3 -march=native -DNDEBUG" \
		$(BENCH_SRC:bench/%.c=$(BUILD)/bench-o3/bench/%) $(BUILD)/bench-o3/ctcsim-server
	@for b in $(BENCH_SRC:bench/%.c=$(BUILD)/bench-o3/bench/%); do echo "== $$b"; $$b || exit 1; done
	@echo "== bench/bench_server.sh"
	@sh bench/bench_server.sh $(BUILD)/bench-o3/ctcsim-server

clean:
	rm -rf $(BUILD)

-include $(LIB_OBJ:.o=.d) $(APP_OBJ:.o=.d) $(MAINS:server/%.c=$(BUILD)/obj/server/%.d) $(SUPPORT_OBJ:.o=.d) $(TEST_BIN:=.d) $(BENCH_BIN:=.d)

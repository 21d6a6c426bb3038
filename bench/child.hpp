#pragma once
// Runs one benchmark case in a forked child, so that its peak RSS is its own (benchmarks).

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <type_traits>

/// Runs `body` (returning a trivially copyable R) in a forked child and returns its result,
/// with the child's peak RSS (kB) in `max_rss_kb`; a default R when the child fails.
template <typename R, typename Body>
R run_in_child(Body body, long& max_rss_kb) {
  static_assert(std::is_trivially_copyable_v<R>, "results cross a pipe as bytes");
  max_rss_kb = 0;
  int fd[2];
  if (pipe(fd) != 0) return R{};
  const pid_t pid = fork();
  if (pid == 0) {
    close(fd[0]);
    const R r = body();
    if (write(fd[1], &r, sizeof r) != sizeof r) _exit(1);
    _exit(0);
  }
  close(fd[1]);
  R r{};
  const bool ok = read(fd[0], &r, sizeof r) == sizeof r;
  close(fd[0]);
  int status = 0;
  struct rusage ru;
  wait4(pid, &status, 0, &ru);
  if (!ok) return R{};
  max_rss_kb = ru.ru_maxrss;
  return r;
}

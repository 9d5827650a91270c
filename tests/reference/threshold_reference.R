# threshold_reference.R — an independent reference for taslab's threshold fit (study/src/study_threshold.c, issue 28):
# the same model written from its definition in study_threshold.h, maximised with R's optim (L-BFGS-B on the bounded
# parameters, from several starts) and its 95% profile-likelihood interval found with uniroot; Gauss-Hermite nodes by
# Golub-Welsch (eigen of the Jacobi matrix), not GSL. Makes a seeded data set and the reference values:
#   Rscript tests/reference/threshold_reference.R   (writes threshold_data.csv and threshold_reference.csv here)
# Model: x = log2 T; an observer with shift u (~ N(0, sd^2), one per participant) prefers the reference with
# psi = 1/2 + (1/2 - lapse) * pnorm(slope * (x - theta - u) + qnorm(1/4 / (1/2 - lapse))); a "same" answer counts
# y = 1/2 (likelihood psi^y (1 - psi)^(1 - y)). Bounds: lapse 0..0.1, sd 0..3, slope 0.1..20.
here <- dirname(sub("--file=", "", grep("--file=", commandArgs(FALSE), value = TRUE)))
set.seed(20261126)
levels <- c(2, 4, 8, 16, 32, 64)
psi <- function(x, theta, slope, lapse) 0.5 + (0.5 - lapse) * pnorm(slope * (x - theta) + qnorm(0.25 / (0.5 - lapse)))
make <- function(P, reps, theta, sd, slope, lapse, ties) {
  rows <- NULL
  for (i in 1:P) {
    u <- rnorm(1, 0, sd)
    for (T in rep(levels, reps)) {
      p <- psi(log2(T), theta + u, slope, lapse)
      tie <- ties * (1 - abs(2 * p - 1))
      r <- runif(1)
      y <- if (r < p - tie / 2) 1 else if (r < p + tie / 2) 0.5 else 0
      rows <- rbind(rows, data.frame(set = 0, participant = i, T = T, y = y))
    }
  }
  rows
}
# set 1: 24 participants x 6 levels x 2, t_jnd 12, sd 0.5; set 2: 16 x 6 x 1, t_jnd 40, sd 0.8 (an upper end beyond
# the range); set 3: 12 participants who see little (t_jnd 200: p_ref below 0.75 everywhere: inf).
d1 <- make(24, 2, log2(12), 0.5, 1.5, 0.02, 0.2); d1$set <- 1
d2 <- make(16, 1, log2(40), 0.8, 1.5, 0.02, 0.2); d2$set <- 2
d3 <- make(12, 1, log2(200), 0.3, 1.5, 0.02, 0.3); d3$set <- 3
data <- rbind(d1, d2, d3)
write.csv(data, file.path(here, "threshold_data.csv"), row.names = FALSE, quote = FALSE)

gh <- function(n) { # probabilists' Hermite: nodes and weights for N(0, 1), weights sum to 1
  J <- matrix(0, n, n)
  for (k in 1:(n - 1)) J[k, k + 1] <- J[k + 1, k] <- sqrt(k)
  e <- eigen(J, symmetric = TRUE)
  list(x = e$values, w = e$vectors[1, ]^2)
}
q <- gh(24)
agg <- function(d) { # per participant x level: trials (N) and the sum of y (K)
  d$pf <- factor(d$participant); d$lf <- factor(d$T, levels = levels)
  list(N = unclass(table(d$pf, d$lf)), K = unclass(xtabs(y ~ pf + lf, d)), x = log2(levels))
}
loglik <- function(a, theta, slope, lapse, sd) {
  lp <- sapply(seq_along(q$x), function(k) {
    p <- psi(a$x, theta + sd * q$x[k], slope, lapse)
    p <- pmin(pmax(p, 1e-12), 1 - 1e-12)
    as.vector(a$K %*% log(p) + (a$N - a$K) %*% log1p(-p)) + log(q$w[k])
  })
  m <- apply(lp, 1, max)
  sum(m + log(rowSums(exp(lp - m))))
}
lower <- c(0.1, 0, 0); upper <- c(20, 0.1, 3)
prof <- function(d, theta) { # max over slope, lapse, sd at theta, from several starts
  best <- -Inf
  for (s0 in list(c(1.5, 0.02, 0.3), c(0.7, 0.05, 1), c(4, 0.01, 0.1), c(1, 0.001, 2)))
    best <- max(best, -optim(s0, function(v) -loglik(d, theta, v[1], v[2], v[3]), method = "L-BFGS-B",
                             lower = lower, upper = upper)$value)
  best
}
out <- NULL
for (s in 1:3) {
  d <- agg(data[data$set == s, ])
  xs <- log2(range(levels))
  grid <- seq(xs[1] - 3, xs[2] + 3, by = 0.25)
  pl <- sapply(grid, function(t) prof(d, t))
  o <- optimize(function(t) -prof(d, t), c(max(xs[1] - 3, grid[which.max(pl)] - 0.5), min(xs[2] + 3, grid[which.max(pl)] + 0.5)),
                tol = 1e-5)
  theta <- o$minimum; lmax <- -o$objective
  dev <- function(t) 2 * (lmax - prof(d, t)) - qchisq(0.95, 1)
  lo <- if (dev(xs[1] - 3) > 0) uniroot(dev, c(xs[1] - 3, theta), tol = 1e-5)$root else -Inf
  hi <- if (dev(xs[2] + 3) > 0) uniroot(dev, c(theta, xs[2] + 3), tol = 1e-5)$root else Inf
  out <- rbind(out, data.frame(set = s, theta = theta, theta_lo = lo, theta_hi = hi, loglik = lmax))
}
write.csv(out, file.path(here, "threshold_reference.csv"), row.names = FALSE, quote = FALSE)
print(out)

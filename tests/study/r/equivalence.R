# Equivalence of identify-real (2-AFC) and 2-AC, computed by hand in R for
# tests/study/test_equivalence_r_oracle.cpp (doorbench's own code is in
# study/statistics/discrimination.cpp):
#   Rscript equivalence.R 2afc CORRECT N MARGIN
#   Rscript equivalence.R 2ac PREFER_FIRST NO_PREFERENCE PREFER_SECOND MARGIN
# prints "NAME VALUE" lines: the 95 % interval of d' (ci_low, ci_high), the p-value of the
# test of no difference (p), the two one-sided tests' p-value against ±MARGIN (p_tost), and
# the verdict as a number: 1 a difference found (p < 0.05), 2 equivalent (the interval inside
# (-MARGIN, MARGIN)), 3 neither, 4 a difference found inside the margin.
args <- commandArgs(trailingOnly = TRUE)
mode <- args[1]
level <- 0.95
verdict <- function(p, low, high, margin) {
  within <- low > -margin && high < margin
  if (p < 1 - level) return(if (within) 4 else 1)
  if (within) 2 else 3
}
out <- function(name, value) cat(name, sprintf("%.15g", value), "\n")

if (mode == "2afc") {
  correct <- as.numeric(args[2]); n <- as.numeric(args[3]); margin <- as.numeric(args[4])
  test <- binom.test(correct, n, 0.5, conf.level = level)
  ci <- sqrt(2) * qnorm(test$conf.int)
  # Pc at the margins: d' = ±margin.
  upper <- pnorm(margin / sqrt(2)); lower <- pnorm(-margin / sqrt(2))
  p_tost <- max(pbinom(correct, n, upper),                  # H0: d' >= margin
                pbinom(correct - 1, n, lower, lower.tail = FALSE))  # H0: d' <= -margin
  out("ci_low", ci[1]); out("ci_high", ci[2]); out("p", test$p.value); out("p_tost", p_tost)
  out("verdict", verdict(test$p.value, ci[1], ci[2], margin))
} else if (mode == "2ac") {
  n <- as.numeric(args[2:4]); margin <- as.numeric(args[5])
  loglik <- function(tau, d) {
    p1 <- pnorm((-tau - d) / sqrt(2))
    p3 <- pnorm((tau - d) / sqrt(2), lower.tail = FALSE)
    p <- c(p1, 1 - p1 - p3, p3)
    sum(ifelse(n > 0, n * log(pmax(p, 1e-300)), 0))
  }
  profile <- function(d) {
    if (n[2] == 0) return(loglik(0, d))
    optimize(function(tau) loglik(tau, d), c(0, 10 + abs(d)), maximum = TRUE, tol = 1e-12)$objective
  }
  q <- qnorm((1 + level) / 2)
  if (n[1] > 0 && n[3] > 0) {
    gamma <- cumsum(n)[1:2] / sum(n)
    z <- sqrt(2) * qnorm(gamma)
    d_hat <- -(z[1] + z[2]) / 2
    top <- loglik((z[2] - z[1]) / 2, d_hat)
  } else {
    # Nobody preferred one of the two: d' is infinite, the likelihood's supremum the answers'
    # shares.
    d_hat <- if (n[1] == 0) Inf else -Inf
    top <- sum(n[n > 0] * log(n[n > 0] / sum(n)))
  }
  root <- function(d) sign(d_hat - d) * sqrt(2 * max(0, top - profile(d)))
  below <- if (is.finite(d_hat)) c(d_hat - 20, d_hat) else c(-20, 20)
  above <- if (is.finite(d_hat)) c(d_hat, d_hat + 20) else c(-20, 20)
  low <- if (d_hat == -Inf) -Inf else uniroot(function(d) root(d) - q, below, tol = 1e-12)$root
  high <- if (d_hat == Inf) Inf else uniroot(function(d) root(d) + q, above, tol = 1e-12)$root
  p <- 2 * pnorm(abs(root(0)), lower.tail = FALSE)
  p_tost <- max(pnorm(root(margin)), pnorm(root(-margin), lower.tail = FALSE))
  out("dprime", d_hat); out("ci_low", low); out("ci_high", high); out("p", p)
  out("p_tost", p_tost); out("verdict", verdict(p, low, high, margin))
} else {
  stop("unknown mode ", mode)
}

# Independent estimates of the preference scale for tests/study/test_preference_oracle.cpp:
#   Rscript preference_oracle.R MODE TRIALS.csv
# reads the trials table's preference rows and prints one line per parameter, "NAME VALUE",
# the worths of every variant but the first (the reference, worth 0) named by the variant,
# and the quasi-variance of every variant's worth, reference included, as "qv_NAME VALUE"
# (qvcalc, Firth & de Menezes 2004: of BTabilities for BTm, of the worths' covariance block
# for glm).
# MODE:
#   btm        Bradley-Terry, BradleyTerry2::BTm(~ player)
#   btm-order  Bradley-Terry with a first-position advantage, BTm(~ player + at.home), the
#              first presentation taken as "home"
#   davidson   Davidson's ties with the first-position advantage, written as a Poisson
#              log-linear model (one nuisance intercept per ordered pair, the multinomial
#              logit's equivalent) and fitted by R's glm; prints also "delta" and "log_nu"
args <- commandArgs(trailingOnly = TRUE)
mode <- args[1]
d <- read.csv(args[2], stringsAsFactors = FALSE, colClasses = "character")
d <- d[d$question %in% c("preference", "preference-2ac"), ]
lev <- unique(as.vector(rbind(d$first, d$second)))  # order of first appearance
tight <- glm.control(epsilon = 1e-14, maxit = 100)

if (mode == "btm" || mode == "btm-order") {
  suppressPackageStartupMessages(library(BradleyTerry2))
  first <- data.frame(player = factor(d$first, levels = lev), at.home = 1)
  second <- data.frame(player = factor(d$second, levels = lev), at.home = 0)
  won <- as.numeric(d$answer == "1")
  form <- if (mode == "btm") ~ player else ~ player + at.home
  fit <- BTm(won, first, second, formula = form, id = "player", refcat = lev[1],
             control = tight)
  co <- coef(fit)
  for (v in lev[-1]) cat(v, sprintf("%.15g", co[paste0("player", v)]), "\n")
  if (mode == "btm-order") cat("delta", sprintf("%.15g", co["at.home"]), "\n")
  if (length(lev) >= 3) {
    suppressPackageStartupMessages(library(qvcalc))
    qv <- qvcalc(BTabilities(fit))$qvframe
    for (v in lev) cat(paste0("qv_", v), sprintf("%.15g", qv[v, "quasiVar"]), "\n")
  }
} else if (mode == "davidson") {
  # One row per trial and outcome (first, second, same); y = 1 for the answer given.
  n <- nrow(d)
  k <- length(lev)
  i <- match(d$first, lev)
  j <- match(d$second, lev)
  outcome <- rep(c("1", "2", "same"), times = n)
  trial <- rep(seq_len(n), each = 3)
  y <- as.numeric(rep(d$answer, each = 3) == outcome)
  x <- matrix(0, 3 * n, k - 1 + 2)
  colnames(x) <- c(paste0("w_", lev[-1]), "delta", "log_nu")
  for (r in seq_len(3 * n)) {
    t <- trial[r]
    wi <- if (i[t] > 1) i[t] - 1 else 0
    wj <- if (j[t] > 1) j[t] - 1 else 0
    share <- switch(outcome[r], "1" = c(1, 0), "2" = c(0, 1), "same" = c(0.5, 0.5))
    if (wi > 0) x[r, wi] <- x[r, wi] + share[1]
    if (wj > 0) x[r, wj] <- x[r, wj] + share[2]
    x[r, "delta"] <- share[1]
    x[r, "log_nu"] <- as.numeric(outcome[r] == "same")
  }
  cell <- factor(paste(i[trial], j[trial]))  # an ordered pair's rows share an intercept
  # Counts per ordered pair and outcome (the Poisson trick needs the cell totals).
  key <- paste(cell, outcome)
  counts <- tapply(y, key, sum)
  first_row <- !duplicated(key)
  fit <- glm(counts[key[first_row]] ~ 0 + cell[first_row] + x[first_row, ],
             family = poisson, control = tight)
  co <- coef(fit)
  names(co) <- sub("^x\\[first_row, \\]", "", names(co))
  for (v in lev[-1]) cat(v, sprintf("%.15g", co[paste0("w_", v)]), "\n")
  cat("delta", sprintf("%.15g", co["delta"]), "\n")
  cat("log_nu", sprintf("%.15g", co["log_nu"]), "\n")
  if (k >= 3) {
    # The worths' covariance, the reference's row and column 0, through qvcalc.
    suppressPackageStartupMessages(library(qvcalc))
    block <- vcov(fit)[paste0("x[first_row, ]w_", lev[-1]), paste0("x[first_row, ]w_", lev[-1])]
    covmat <- matrix(0, k, k, dimnames = list(lev, lev))
    covmat[-1, -1] <- block
    qv <- qvcalc(covmat)$qvframe
    for (v in lev) cat(paste0("qv_", v), sprintf("%.15g", qv[v, "quasiVar"]), "\n")
  }
} else {
  stop("unknown mode ", mode)
}

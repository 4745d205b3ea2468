# The independent fit of the ratings tests (tests/study/test_ratings_r_oracle.cpp): R's
# ordinal package (Christensen) on a CSV of participant,variant,rating.
# Usage: Rscript clmm_fit.R DATA.csv NAGQ OUT.csv   (NAGQ 0: clm, the fixed-effect model)
# Writes name,value,se rows: the thresholds ("1|2", ...), the variant effects ("variantV2", ...),
# "sd" (the participants' random-intercept SD) and "logLik".
args <- commandArgs(trailingOnly = TRUE)
suppressPackageStartupMessages(library(ordinal))
d <- read.csv(args[1], stringsAsFactors = FALSE)
d$variant <- factor(d$variant, levels = unique(d$variant))  # the first seen is the reference
d$rating <- factor(d$rating, levels = sort(unique(d$rating)), ordered = TRUE)
d$participant <- factor(d$participant)
nagq <- as.integer(args[2])
if (nagq == 0) {
  m <- clm(rating ~ variant, data = d, link = "logit",
           control = clm.control(gradTol = 1e-10, maxIter = 1000))
  sd <- 0
} else {
  m <- clmm(rating ~ variant + (1 | participant), data = d, link = "logit", nAGQ = nagq,
            control = clmm.control(gradTol = 1e-8, maxIter = 1000))
  sd <- attr(VarCorr(m)$participant, "stddev")[[1]]
}
co <- coef(m)
co <- co[!startsWith(names(co), "ST")]
se <- sqrt(diag(vcov(m)))[names(co)]
out <- data.frame(name = c(names(co), "sd", "logLik"),
                  value = c(co, sd, as.numeric(logLik(m))),
                  se = c(se, NA, NA))
write.csv(out, args[3], row.names = FALSE)

# A constant-stimuli trials table from published data, for the thresholds' benchmark
# (docs/PERFORMANCE.md, "Thresholds: 3918 trials"): MASS's menarche data (Milicer &
# Szczotka 1966, 3918 Warsaw girls in 25 age groups; Venables & Ripley's MASS, Debian
# r-cran-mass) as `stronger:age` trials, the comparison an age group, the reference 13
# years, "the comparison felt stronger" when the girl had reached menarche.
#   Rscript bench/menarche_trials.R OUT.csv one     # one participant answering all 3918
#   Rscript bench/menarche_trials.R OUT.csv girls   # each girl a participant of one trial
library(MASS)
args <- commandArgs(trailingOnly = TRUE)
if (length(args) != 2 || !(args[2] %in% c("one", "girls")))
  stop("usage: Rscript menarche_trials.R OUT.csv one|girls")
rows <- character(0)
girl <- 0
for (r in seq_len(nrow(menarche))) {
  for (k in seq_len(menarche$Total[r])) {
    girl <- girl + 1
    reached <- k <= menarche$Menarche[r]
    comparison_first <- girl %% 2 == 1
    if (args[2] == "girls") {
      who <- sprintf("G%04d", girl); trial <- 1
      comparison <- sprintf("age*%.6f", menarche$Age[r] / 13); reference <- "age*1"
    } else {
      who <- "P01"; trial <- girl
      comparison <- sprintf("age*%.2f", menarche$Age[r]); reference <- "age*13"
    }
    first <- if (comparison_first) comparison else reference
    second <- if (comparison_first) reference else comparison
    answer <- if (reached == comparison_first) "1" else "2"
    rows <- c(rows, sprintf("%s,menarche,%d,stronger:age,%s,%s,%s", who, trial, first, second,
                            answer))
  }
}
writeLines(c("participant,block,trial,question,first,second,answer", rows), args[1])

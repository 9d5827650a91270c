#!/usr/bin/Rscript
# study_reference.R — independent reference statistics for tests/test_study.c from R (Debian r-base-core):
# per condition Q = mean rating with t.test's 95% CI, qnorm-based JND, and the repeated-measures ANOVA per T
# with factors camera (motion class) x scene from aov(... + Error(participant/(camera*scene))), plus the
# Greenhouse-Geisser epsilons and corrected p values from anova.mlm(test = "Spherical") (for every effect, camera's
# two levels included: R says epsilon 1 there itself); post hoc paired t.test between the levels of each factor (each
# participant's mean over the other factor's cells) with p.adjust(method = "bonferroni"); and per condition row the
# JOD (-JND) with a percentile bootstrap over participants (B = 20000, quantile type 7), the statistic taslab's
# tally bootstraps, drawn by R's own generator (set.seed(1)).
# Regenerate: Rscript tests/reference/study_reference.R tests/reference/study_ratings.csv > tests/reference/study_reference.csv
args <- commandArgs(trailingOnly = TRUE)
d <- read.csv(args[1])
d$participant <- factor(d$participant); d$scene <- factor(d$scene, levels = c("calm", "dynamic", "moderate"))
d$camera_motion <- factor(d$camera_motion, levels = c("stationary", "moving"))
out <- data.frame(kind = character(), T = numeric(), key = character(), value = numeric())
add <- function(kind, T, key, value) out[nrow(out) + 1, ] <<- list(kind, T, key, value)
for (TT in sort(unique(d$T))) {
  s <- d[d$T == TT, ]
  for (sc in levels(s$scene)) for (cam in unique(s$camera)) {
    x <- s$rating[s$scene == sc & s$camera == cam]
    if (length(x) == 0) next
    tt <- t.test(x)
    k <- paste(sc, cam, sep = "/")
    add("Q", TT, k, mean(x)); add("Q_lo", TT, k, tt$conf.int[1]); add("Q_hi", TT, k, tt$conf.int[2])
    p <- (sum(x > 0) + 0.5 * sum(x == 0)) / length(x)
    add("jnd", TT, k, qnorm(min(max(p, 0.5 / length(x)), 1 - 0.5 / length(x))) / qnorm(0.75))
  }
  a <- summary(aov(rating ~ camera_motion * scene + Error(participant / (camera_motion * scene)), data = s))
  for (st in names(a)) {
    tab <- a[[st]][[1]]
    rn <- trimws(rownames(tab))
    for (i in seq_along(rn)) if (rn[i] != "Residuals") {
      eff <- sub("camera_motion", "camera", gsub(":", ":", rn[i]))
      add("F", TT, eff, tab[i, "F value"]); add("p", TT, eff, tab[i, "Pr(>F)"])
      add("df1", TT, eff, tab[i, "Df"]); add("df2", TT, eff, tab[nrow(tab), "Df"])
    }
  }
  # Greenhouse-Geisser via the multivariate model on the participant x cell matrix.
  s$cell <- interaction(s$camera_motion, s$scene, sep = "_")
  w <- tapply(s$rating, list(s$participant, s$cell), mean)
  idata <- expand.grid(camera = factor(c("stationary", "moving"), levels = c("stationary", "moving")),
                       scene = factor(c("calm", "dynamic", "moderate")))
  w <- w[, paste(idata$camera, idata$scene, sep = "_")]
  fit <- lm(w ~ 1)
  for (eff in c("camera", "scene", "camera:scene")) {
    X <- switch(eff, camera = ~1, scene = ~camera, ~camera + scene)
    M <- switch(eff, camera = ~camera, scene = ~camera + scene, ~camera * scene)
    an <- anova(fit, M = M, X = X, idata = idata, test = "Spherical")
    h <- grep("Greenhouse-Geisser epsilon", attr(an, "heading"), value = TRUE)
    add("epsilon_gg", TT, eff, as.numeric(sub(".*:", "", h)))  # printed with 4 decimals
    add("p_gg", TT, eff, an[1, "G-G Pr"])
  }
  # Post hoc: paired t tests between levels, Bonferroni over the pairs of one factor; keys FACTOR/LEVEL_1/LEVEL_2,
  # written in both orders (t changes sign).
  for (f in c("camera", "scene")) {
    lv <- if (f == "camera") levels(s$camera_motion) else levels(s$scene)
    m <- sapply(lv, function(l) rowMeans(w[, if (f == "camera") idata$camera == l else idata$scene == l, drop = FALSE]))
    prs <- combn(length(lv), 2)
    tt <- apply(prs, 2, function(ij) t.test(m[, ij[1]], m[, ij[2]], paired = TRUE))
    pb <- p.adjust(sapply(tt, function(x) x$p.value), method = "bonferroni")
    for (k in seq_len(ncol(prs))) for (o in 1:2) {
      ij <- if (o == 1) prs[, k] else rev(prs[, k])
      key <- paste(f, lv[ij[1]], lv[ij[2]], sep = "/")
      add("posthoc_t", TT, key, if (o == 1) tt[[k]]$statistic else -tt[[k]]$statistic)
      add("posthoc_df", TT, key, tt[[k]]$parameter)
      add("posthoc_p", TT, key, tt[[k]]$p.value); add("posthoc_p_bonferroni", TT, key, pb[k])
    }
  }
  # JOD = -JND per row (scene/camera, and all/all pooled) with its 95% percentile bootstrap over participants: a
  # resample draws participants with replacement and pools their ratings (a participant drawn twice counts twice).
  jod <- function(x) {
    p <- (sum(x > 0) + 0.5 * sum(x == 0)) / length(x)
    -qnorm(min(max(p, 0.5 / length(x)), 1 - 0.5 / length(x))) / qnorm(0.75)
  }
  rows <- c(lapply(levels(s$scene), function(sc) lapply(unique(s$camera), function(cam) c(sc, cam))), list(list(c("all", "all"))))
  for (r in unlist(rows, recursive = FALSE)) {
    x <- if (r[1] == "all") s else s[s$scene == r[1] & s$camera == r[2], ]
    by <- split(x$rating, x$participant)
    set.seed(1)
    b <- replicate(20000, jod(unlist(by[sample(length(by), replace = TRUE)])))
    k <- paste(r[1], r[2], sep = "/")
    add("jod", TT, k, jod(x$rating))
    add("jod_lo", TT, k, quantile(b, 0.025, type = 7)); add("jod_hi", TT, k, quantile(b, 0.975, type = 7))
  }
}
write.csv(out, row.names = FALSE)

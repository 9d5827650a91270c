#!/usr/bin/Rscript
# study_reference.R — independent reference statistics for tests/test_study.c from R (Debian r-base-core):
# per condition Q = mean rating with t.test's 95% CI, qnorm-based JND, and the repeated-measures ANOVA per T
# with factors camera (motion class) x scene from aov(... + Error(participant/(camera*scene))), plus the
# Greenhouse-Geisser epsilons and corrected p values from anova.mlm(test = "Spherical").
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
  for (eff in c("scene", "camera:scene")) {
    X <- if (eff == "scene") ~camera else ~camera + scene
    M <- if (eff == "scene") ~camera + scene else ~camera * scene
    an <- anova(fit, M = M, X = X, idata = idata, test = "Spherical")
    h <- grep("Greenhouse-Geisser epsilon", attr(an, "heading"), value = TRUE)
    add("epsilon_gg", TT, eff, as.numeric(sub(".*:", "", h)))  # printed with 4 decimals
    add("p_gg", TT, eff, an[1, "G-G Pr"])
  }
}
write.csv(out, row.names = FALSE)

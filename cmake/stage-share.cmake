# Stages liveprobe's run-time data into DEST (BUILD/share/liveprobe), the folder the program finds
# beside its own (<bin>/../share/liveprobe) in the build tree as in an install: the default
# recording, the stream's web page, and the three.js it draws with (app/web/vendor/three).
# cmake -DSOURCE=<source tree> -DDEST=<folder> -P stage-share.cmake
file(COPY ${SOURCE}/recordings/sky.mkv ${SOURCE}/recordings/sky.mkv.json
     DESTINATION ${DEST}/recordings)
file(COPY ${SOURCE}/app/web/index.html ${SOURCE}/app/web/main.js DESTINATION ${DEST}/web)
set(three ${SOURCE}/app/web/vendor/three)
file(COPY ${three}/three.module.js ${three}/three.core.js
     DESTINATION ${DEST}/web/three)  # (its MIT notice: the package's copyright file)

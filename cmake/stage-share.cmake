# Stages liveprobe's run-time data into DEST (BUILD/share/liveprobe), the folder the program finds
# beside its own (<bin>/../share/liveprobe) in the build tree as in an install: the default
# recording, the stream's web page, and three.js's build where npm has installed it.
# cmake -DSOURCE=<source tree> -DDEST=<folder> -P stage-share.cmake
file(COPY ${SOURCE}/recordings/sky.mkv ${SOURCE}/recordings/sky.mkv.json
     DESTINATION ${DEST}/recordings)
file(COPY ${SOURCE}/app/web/index.html ${SOURCE}/app/web/main.js DESTINATION ${DEST}/web)
set(three ${SOURCE}/app/web/node_modules/three/build)
if(EXISTS ${three}/three.module.js)
  file(COPY ${three}/three.module.js ${three}/three.core.js DESTINATION ${DEST}/web/three)
endif()

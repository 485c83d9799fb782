# Copies the web player's files next to the splatffd binary (<exe dir>/web/player), and the PlayCanvas
# engine when tools/fetch_web_engine.sh has installed it (<exe dir>/web/playcanvas.min.js); without the
# engine the copy is skipped and `export --web` says to run the script. Run with cmake -P:
#   -DSRC_PLAYER=<content/web/player> -DENGINE=<.../playcanvas.min.js> -DDST=<exe dir>/web
file(MAKE_DIRECTORY "${DST}/player")
file(GLOB player_files "${SRC_PLAYER}/*")
foreach(f IN LISTS player_files)
  get_filename_component(name "${f}" NAME)
  file(COPY_FILE "${f}" "${DST}/player/${name}" ONLY_IF_DIFFERENT)
endforeach()
if(EXISTS "${ENGINE}")
  file(COPY_FILE "${ENGINE}" "${DST}/playcanvas.min.js" ONLY_IF_DIFFERENT)
else()
  file(REMOVE "${DST}/playcanvas.min.js")
endif()
